import numpy as np
import pytest

from pose_io import BODY15, BODY25, COCO18, MEDIAPIPE33, InputError, PoseTrack


def test_missing_is_nan_and_zero_confidence(walking_track):
    joints = walking_track.joints.copy()
    conf = walking_track.confidence.copy()
    joints[3, 4] = np.nan
    conf[5, 7] = 0.0
    track = walking_track.replace(joints=joints, confidence=conf)
    assert track.confidence[3, 4] == 0.0
    assert np.isnan(track.joints[5, 7]).all()
    assert track.missing.sum() == 2


def test_arrays_are_read_only(walking_track):
    with pytest.raises(ValueError):
        walking_track.joints[0, 0, 0] = 1.0


@pytest.mark.parametrize(
    "joints, conf, message",
    [
        (np.zeros((0, 25, 2)), np.zeros((0, 25)), "no frames"),
        (np.zeros((3, 18, 2)), np.ones((3, 18)), "has 25 joints"),
        (np.zeros((3, 25, 3)), np.ones((3, 25)), "must be"),
        (np.full((3, 25, 2), np.inf), np.ones((3, 25)), "infinite"),
        (np.zeros((3, 25, 2)), np.full((3, 25), 2.0), "confidence"),
    ],
)
def test_constructor_rejects_bad_arrays(joints, conf, message):
    with pytest.raises(InputError, match=message):
        PoseTrack(joints, conf, 30.0, (64, 64), "body25")


def test_coco18_to_body15_makes_mid_hip(walking_track):
    coco = walking_track.to_layout("coco18")
    assert coco.layout == "coco18" and coco.joints.shape[1] == 18
    back = coco.to_layout("body15")
    hips = walking_track.joints[:, [BODY25.index("l_hip"), BODY25.index("r_hip")]].mean(axis=1)
    np.testing.assert_allclose(back.joint("mid_hip"), hips, atol=1e-4)


def test_mediapipe_to_body25_makes_neck_and_toes():
    joints = np.random.default_rng(1).uniform(0, 100, (2, 33, 2)).astype(np.float32)
    track = PoseTrack(joints, np.ones((2, 33)), 25.0, (100, 100), "mediapipe33")
    body = track.to_layout("body25")
    mp = MEDIAPIPE33
    neck = joints[:, [mp.index("l_shoulder"), mp.index("r_shoulder")]].mean(axis=1)
    np.testing.assert_allclose(body.joint("neck"), neck, atol=1e-4)
    np.testing.assert_allclose(body.joint("l_big_toe"), joints[:, mp.index("l_foot_index")])
    assert body.missing[:, BODY25.index("l_small_toe")].all()


def test_derived_joint_is_missing_when_a_part_is_missing():
    joints = np.ones((1, 18, 2), dtype=np.float32)
    joints[0, COCO18.index("l_hip")] = np.nan
    track = PoseTrack(joints, np.ones((1, 18)), 30.0, (10, 10), "coco18").to_layout("body15")
    assert track.missing[0, BODY15.index("mid_hip")]
