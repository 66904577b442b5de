"""The synthetic performer's detail points (eyes, ears, mouth, hands, heels) where the renderer draws them."""

from __future__ import annotations

import numpy as np

from clone.synth import get_character, render_performance
from clone.synth.appearance import BodyShape
from clone.synth.details import detail_track
from pose_io.layouts import get_layout
from retarget.world.skeleton import WORLD_JOINTS
from tests.clone.synth.bodies import SCALE, SIZE, motion_of, project, standing, waving

BODY31 = get_layout("body31")


def _points(yaw: float) -> dict[str, np.ndarray]:
    xy, depth = project(standing(), yaw)
    track = detail_track(xy[None], depth[None], SCALE, WORLD_JOINTS, BodyShape(), 30.0, (SIZE, SIZE))
    assert track.layout == "body31" and not track.missing.any()
    return {n: track.joints[0, BODY31.index(n)] for n in BODY31.joints}


def test_front_view_places_the_face_hands_and_heels_where_they_are_drawn() -> None:
    p = _points(0.0)
    shape = BodyShape()
    # Facing the camera: her left is on the image's right; eyes above the nose's tip row, the mouth below it.
    assert p["l_eye"][0] > p["nose"][0] > p["r_eye"][0]
    assert p["mouth_left"][0] > p["mouth_right"][0]
    assert max(p["l_eye"][1], p["r_eye"][1]) < min(p["mouth_left"][1], p["mouth_right"][1])
    assert p["l_ear"][0] > p["l_eye"][0] and p["r_ear"][0] < p["r_eye"][0]
    head_px = shape.head_radius * SCALE
    for name in ("l_eye", "r_eye", "l_ear", "r_ear", "mouth_left", "mouth_right"):
        assert np.linalg.norm(p[name] - p["nose"]) < 2.5 * head_px
    for side in ("l", "r"):
        wrist = p[f"{side}_wrist"]
        for finger in ("thumb", "index", "pinky"):
            reach = np.linalg.norm(p[f"{side}_{finger}"] - wrist) / SCALE
            assert 0.2 * shape.hand_length < reach < shape.hand_length + 2 * shape.hand_radius
        # the heel behind the ankle, away from the toe
        toe, ankle, heel = p[f"{side}_big_toe"], p[f"{side}_ankle"], p[f"{side}_heel"]
        assert np.linalg.norm(heel - toe) > np.linalg.norm(ankle - toe) - 1e-6


def test_back_view_swaps_the_eyes_as_they_appear() -> None:
    front, back = _points(0.0), _points(180.0)
    assert front["l_eye"][0] > front["r_eye"][0]
    assert back["l_eye"][0] < back["r_eye"][0]
    assert back["l_ear"][0] < back["r_ear"][0]


def test_render_performance_gives_the_detailed_track_on_request() -> None:
    motion = motion_of(waving(4))
    skeleton, look, _ = get_character("average")
    _, plain, _ = render_performance(motion, skeleton, look, yaw=20.0, size=96)
    frames, detailed, _ = render_performance(motion, skeleton, look, yaw=20.0, size=96, details=True)
    assert detailed.layout == "body31" and not detailed.missing.any()
    assert len(list(frames)) == 4
    # the joints the plain BODY_25 track has are the same points
    for name in ("nose", "neck", "r_wrist", "l_ankle", "l_big_toe"):
        np.testing.assert_allclose(detailed.joint(name), plain.joint(name), atol=1e-4)
