"""pose_io.details: detail points carried through their parent bones, and which way a body faces."""

from __future__ import annotations

import numpy as np
import pytest

from pose_io.details import PARENT_BONES, carry_details, facing
from pose_io.layouts import BODY15, BODY31, MEDIAPIPE33, convert_arrays
from tests.clone.train_ref.helpers import figure_track


def detailed(frames: int = 6) -> np.ndarray:
    """[T, 31, 2] a body31 pose: the figure's body15 and detail points near their parents."""
    body = figure_track(frames, width=200, height=200).joints
    out = np.full((frames, len(BODY31), 2), np.nan, np.float32)
    out[:, :15] = body
    rng = np.random.default_rng(0)
    for name, (_a, b) in PARENT_BONES.items():
        out[:, BODY31.index(name)] = body[:, BODY15.index(b)] + rng.normal(0, 6, (frames, 2))
    return out


def similarity(points: np.ndarray, angle: float, scale: float, shift: tuple[float, float]) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return (points @ np.array([[c, s], [-s, c]]).T * scale + np.array(shift)).astype(np.float32)


def test_every_detail_has_a_body15_parent_bone():
    assert set(PARENT_BONES) == set(BODY31.joints[15:])
    for a, b in PARENT_BONES.values():
        assert BODY15.has(a) and BODY15.has(b)


def test_details_follow_a_similarity_of_the_whole_body():
    source = detailed()
    moved = similarity(source, 0.7, 1.8, (30.0, -12.0))
    out = carry_details(moved[:, :15], source)
    np.testing.assert_allclose(out, moved, atol=1e-3)


def test_each_point_moves_with_its_own_bone():
    source = detailed(1)
    body = source[:, :15].copy()
    wrist, elbow = BODY15.index("r_wrist"), BODY15.index("r_elbow")
    body[:, wrist] = body[:, elbow] + 2.0 * (body[:, wrist] - body[:, elbow])  # the forearm twice as long
    out = carry_details(body, source)
    thumb = BODY31.index("r_thumb")
    np.testing.assert_allclose(out[0, thumb] - body[0, wrist], 2.0 * (source[0, thumb] - source[0, wrist]),
                               atol=1e-3)
    # The face and the other hand did not move.
    for name in ("r_eye", "mouth_left", "l_thumb", "l_big_toe"):
        np.testing.assert_allclose(out[0, BODY31.index(name)], source[0, BODY31.index(name)], atol=1e-3)


def test_missing_points_and_bones_stay_missing():
    source = detailed(3)
    source[0, BODY31.index("l_index")] = np.nan  # the point
    source[1, BODY15.index("neck")] = np.nan  # the driver's face bone
    body = source[:, :15].copy()
    body[2, BODY15.index("r_knee")] = body[2, BODY15.index("r_ankle")]  # fine in the body: only a source bone counts
    source[2, BODY15.index("r_knee")] = source[2, BODY15.index("r_ankle")]  # no length
    out = carry_details(body, source)
    assert np.isnan(out[0, BODY31.index("l_index")]).all() and np.isfinite(out[0, BODY31.index("l_thumb")]).all()
    assert np.isnan(out[1, BODY31.indices(["r_eye", "l_ear", "mouth_right"])]).all()
    assert np.isnan(out[2, BODY31.indices(["r_heel", "r_big_toe"])]).all()
    assert np.isfinite(out[2, BODY31.indices(["l_heel", "l_big_toe"])]).all()


def test_facing_tells_front_from_back():
    front = figure_track(1, width=200, height=200).joints  # the figure's left joints are on the image's right
    assert front[0, BODY15.index("l_shoulder"), 0] > front[0, BODY15.index("r_shoulder"), 0]
    back = front.copy()
    back[..., 0] = 200 - back[..., 0]
    side = front.copy()
    side[..., 0] = 100.0
    assert facing(front, BODY15)[0] == pytest.approx(1.0, abs=0.3)
    assert facing(back, BODY15)[0] == pytest.approx(-facing(front, BODY15)[0])
    assert facing(side, BODY15)[0] == 0.0
    unknown = np.full_like(front, np.nan)
    assert facing(unknown, BODY15)[0] == 0.0
    only_hips = front.copy()
    only_hips[0, BODY15.indices(["l_shoulder", "r_shoulder"])] = np.nan
    assert 0 < facing(only_hips, BODY15)[0] <= 1.0


def test_mediapipe_gives_every_body31_point_on_its_own_side():
    joints = np.random.default_rng(1).uniform(0, 100, (2, len(MEDIAPIPE33), 2)).astype(np.float32)
    out, conf = convert_arrays(joints, np.ones(joints.shape[:2], np.float32), MEDIAPIPE33, BODY31)
    assert np.isfinite(out).all() and (conf > 0).all()
    for name in ("mouth_left", "r_pinky", "l_heel"):
        np.testing.assert_array_equal(out[:, BODY31.index(name)], joints[:, MEDIAPIPE33.index(name)])
    # Mirroring swaps the mouth corners as it swaps every other side.
    assert BODY31.joints[BODY31.mirror[BODY31.index("mouth_left")]] == "mouth_right"
