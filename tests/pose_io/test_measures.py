"""pose_io.measures: known values of every body measure on a hand-made stick figure, missing joints, errors."""

from __future__ import annotations

import logging

import numpy as np
import pytest

from pose_io import BODY15, BODY25, InputError
from pose_io import measures as m

# A person standing: nose-neck 20, neck-mid_hip 60, hip-knee 40, knee-ankle 40 (pixels; y grows downwards).
_STAND = {
    "nose": (100, 20), "neck": (100, 40), "r_shoulder": (85, 40), "r_elbow": (85, 70), "r_wrist": (85, 95),
    "l_shoulder": (115, 40), "l_elbow": (115, 70), "l_wrist": (115, 95), "mid_hip": (100, 100),
    "r_hip": (90, 100), "r_knee": (90, 140), "r_ankle": (90, 180), "l_hip": (110, 100), "l_knee": (110, 140),
    "l_ankle": (110, 180),
}
HEIGHT = 20 + 60 + 40 + 40
J = BODY15.index


def stand(frames: int = 6) -> np.ndarray:
    """[T, 15, 2] the standing pose in every frame."""
    pose = np.array([_STAND[n] for n in BODY15.joints], dtype=np.float64)
    return np.repeat(pose[None], frames, axis=0)


def test_as_layout_and_check_joints():
    assert m.as_layout("body25") is BODY25 and m.as_layout(BODY15) is BODY15
    out = m.check_joints(stand().astype(np.float32), BODY15, "x")
    assert out.dtype == np.float64 and out.shape == (6, 15, 2)
    with pytest.raises(InputError, match=r"my track: expected \[T, 15, 2\] joints for body15, got \(6, 25, 2\)"):
        m.check_joints(np.zeros((6, 25, 2)), BODY15, "my track")
    with pytest.raises(InputError, match="expected"):
        m.check_joints(np.zeros((15, 2)), BODY15, "x")


def test_segment_lengths_known_values_and_nan():
    joints = np.array([[[0.0, 0.0], [3.0, 4.0], [np.nan, 1.0]]])  # [1, 3, 2]
    lengths = m.segment_lengths(joints, np.array([[0, 1], [1, 2], [0, 0]]))
    assert lengths.shape == (1, 3)
    assert lengths[0, 0] == 5.0 and np.isnan(lengths[0, 1]) and lengths[0, 2] == 0.0


def test_limb_lengths_follow_the_layouts_limbs():
    lengths = m.limb_lengths(stand(3))
    assert lengths.shape == (3, len(BODY15.limbs))
    limb = {pair: i for i, pair in enumerate(BODY15.limbs)}
    assert lengths[0, limb[("neck", "mid_hip")]] == 60.0
    assert lengths[0, limb[("r_shoulder", "r_elbow")]] == 30.0
    assert lengths[0, limb[("neck", "r_shoulder")]] == 15.0
    with pytest.raises(InputError, match="limb lengths"):
        m.limb_lengths(stand(3), "body25")


def test_reference_limb_lengths_median_quantile_and_never_seen(caplog):
    joints = stand(5)
    forearm = BODY15.limbs.index(("r_elbow", "r_wrist"))
    joints[:, J("r_wrist"), 1] = 70 + np.array([10, 20, 25, 30, 40])  # forearm 10, 20, 25, 30, 40
    np.testing.assert_allclose(m.reference_limb_lengths(joints)[forearm], 25.0)
    assert m.reference_limb_lengths(joints, quantile=1.0)[forearm] == 40.0
    assert m.reference_limb_lengths(joints, quantile=0.75)[forearm] == 30.0
    joints[:, J("l_wrist")] = np.nan
    joints[0, J("nose")] = np.nan  # missing in one frame only: still measured
    with caplog.at_level(logging.WARNING, logger="pose_io.measures"):
        ref = m.reference_limb_lengths(joints)
    never = BODY15.limbs.index(("l_elbow", "l_wrist"))
    assert np.isnan(ref[never]) and np.isfinite(np.delete(ref, never)).all()
    assert ref[BODY15.limbs.index(("neck", "nose"))] == 20.0
    assert "l_elbow-l_wrist" in caplog.text


def test_skeleton_height_adds_head_trunk_and_the_mean_leg():
    assert m.skeleton_height(stand()) == HEIGHT
    # Bone lengths, not the bounding box: bending the knees in some frames does not change it.
    joints = stand(7)
    joints[:3, BODY15.indices(["r_knee", "l_knee"]), 0] += 30
    assert m.skeleton_height(joints, "body15") == HEIGHT
    # One leg longer: the two are averaged.
    joints = stand()
    joints[:, J("l_ankle"), 1] += 20
    assert m.skeleton_height(joints) == HEIGHT + 10
    # Scale invariance: a figure twice as large is twice as tall.
    assert m.skeleton_height(stand() * 2) == 2 * HEIGHT


def test_skeleton_height_of_a_body25_track():
    joints = np.full((4, 25, 2), np.nan)
    joints[:, :15] = stand(4)
    assert m.skeleton_height(joints, BODY25) == HEIGHT


def test_skeleton_heights_per_window_and_missing_bones():
    windows = np.stack([stand(), stand() * 0.5, stand()])  # [3, T, 15, 2]
    windows[2, :, J("nose")] = np.nan
    heights = m.skeleton_heights(windows)
    assert heights.shape == (3,)
    np.testing.assert_allclose(heights[:2], [HEIGHT, HEIGHT / 2])
    assert np.isnan(heights[2])
    with pytest.raises(InputError, match="missing in every frame"):
        m.skeleton_height(windows[2])


def test_foot_points_take_the_lower_ankle():
    joints = stand(3)
    joints[0, J("l_ankle"), 1] = 170  # left foot lifted: the right one is on the ground
    joints[1, J("r_ankle")] = np.nan  # one ankle missing: the other
    joints[2, BODY15.indices(["l_ankle", "r_ankle"])] = np.nan
    feet = m.foot_points(joints, BODY15)
    assert feet.shape == (3, 2)
    np.testing.assert_array_equal(feet[0], _STAND["r_ankle"])
    np.testing.assert_array_equal(feet[1], _STAND["l_ankle"])
    assert np.isnan(feet[2]).all()


def test_apparent_heights_from_the_top_joint_to_the_foot():
    joints = stand(3)
    joints[1, J("nose")] = np.nan  # the neck is the top then
    foot_y = np.array([180.0, 180.0, np.nan])
    np.testing.assert_array_equal(m.apparent_heights(joints, foot_y)[:2], [160.0, 140.0])
    assert np.isnan(m.apparent_heights(joints, foot_y)[2])


def test_motion_spread_known_values():
    joints = np.zeros((4, 2, 2))
    joints[:, 1, 0] = [-10, 10, -10, 10]  # joint 1 swings 10 px either side of its mean
    joints[:, :, 1] += np.arange(4)[:, None] * 100  # both travel down together
    spread = m.motion_spread(joints, height=100.0, root=0)
    np.testing.assert_allclose(spread, [0.0, 0.1])
    with_travel = m.motion_spread(joints, height=100.0)
    assert with_travel[0] == pytest.approx(np.sqrt(np.mean((np.arange(4) * 100 - 150.0) ** 2)) / 100)
    joints[:, 1] = np.nan
    assert np.isnan(m.motion_spread(joints, 100.0, root=0)[1])


def test_amplitude_ratio():
    rng = np.random.default_rng(0)
    moving = stand(20) + rng.normal(0, 5, (20, 15, 2))
    # The same motion on a body twice the size: the same range relative to the height.
    assert m.amplitude_ratio(moving * 2, 2 * HEIGHT, moving, HEIGHT) == pytest.approx(1.0)
    damped = moving.mean(axis=0) + 0.5 * (moving - moving.mean(axis=0))
    assert m.amplitude_ratio(damped, HEIGHT, moving, HEIGHT) == pytest.approx(0.5)
    assert np.isnan(m.amplitude_ratio(moving, HEIGHT, stand(20), HEIGHT))  # the reference does not move
