"""Shortcuts of the track type (PoseTrack.complete, frames, to_layout) give what the checking constructor gives."""

from __future__ import annotations

import numpy as np
import pytest

from pose_io import InputError, PoseTrack
from pose_io.layouts import LAYOUTS, convert_arrays


def _same_track(a: PoseTrack, b: PoseTrack) -> None:
    assert (a.layout, a.fps, a.image_size) == (b.layout, b.fps, b.image_size)
    assert a.joints.dtype == b.joints.dtype == np.float32 and a.confidence.dtype == b.confidence.dtype
    assert a.joints.tobytes() == b.joints.tobytes() and a.confidence.tobytes() == b.confidence.tobytes()
    assert not a.joints.flags.writeable and not a.confidence.flags.writeable


def _outcome(make):
    try:
        return "track", make()
    except (InputError, ValueError) as exc:
        return "error", type(exc), str(exc)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_complete_is_the_constructor_with_confidence_one(dtype):
    joints = np.random.default_rng(0).normal(300, 90, (50, 15, 2)).astype(dtype)
    expected = PoseTrack(joints, np.ones((50, 15)), 25.0, (640, 480), "body15")
    _same_track(PoseTrack.complete(joints, 25.0, (640, 480), "body15"), expected)
    given = joints.copy()
    track = PoseTrack.complete(given, 25.0, (640, 480), "body15", copy=False)
    _same_track(track, expected)
    assert np.shares_memory(track.joints, given) == (dtype == np.float32)  # handed over, not copied
    assert np.shares_memory(PoseTrack.complete(joints, 25.0, (640, 480), "body15").joints, joints) is False


@pytest.mark.parametrize(
    "change",
    ["nan", "inf", "huge", "beyond float32", "far", "fps", "size", "shape", "layout", "empty", "list", "int"],
)
def test_complete_fails_and_falls_back_as_the_constructor_does(change):
    joints = np.random.default_rng(1).normal(300, 90, (20, 15, 2))
    fps, size, layout = 30.0, (640, 480), "body15"
    if change == "nan":
        joints[3, 4] = np.nan  # a missing joint: confidence 0 there
    elif change == "inf":
        joints[2, 1, 0] = np.inf
    elif change == "huge":
        joints[2, 1, 0] = 1e7
    elif change == "beyond float32":
        joints[2, 1, 0] = 3.40282356e38  # rounds to float32's largest, but the constructor refuses it
        fps = -1.0  # and the first error must stay the first
    elif change == "far":
        joints[5, 2] = (-16 * 640 - 1, 10)
    elif change == "fps":
        fps = 0.0
    elif change == "size":
        size = (0, 480)
    elif change == "shape":
        joints = joints[:, :14]
    elif change == "layout":
        layout = "body99"
    elif change == "empty":
        joints = joints[:0]
    elif change == "list":
        joints = joints.tolist()
    elif change == "int":
        joints = joints.astype(np.int64)
    got = _outcome(lambda: PoseTrack.complete(joints, fps, size, layout))
    expected = _outcome(lambda: PoseTrack(joints, np.ones(np.shape(joints)[:2]), fps, size, layout))
    assert got[0] == expected[0]
    if got[0] == "track":
        _same_track(got[1], expected[1])
    else:
        assert got[1:] == expected[1:]


def test_frames_and_layouts_skip_the_checks_but_not_the_result(walking_track):
    joints = walking_track.joints.copy()
    conf = walking_track.confidence.copy()
    conf[4:9, 3] = 0.0  # some missing joints
    track = PoseTrack(joints, conf, 30.0, (640, 480), "body25")
    part = track.frames(5, 17)
    _same_track(part, PoseTrack(track.joints[5:17], track.confidence[5:17], 30.0, (640, 480), "body25"))
    assert not np.shares_memory(part.joints, track.joints)  # a copy: the whole track is not kept alive
    with pytest.raises(InputError, match="no frames"):
        track.frames(7, 7)
    for name in LAYOUTS:
        converted = track.to_layout(name)
        arrays = convert_arrays(track.joints, track.confidence, track.joint_layout, LAYOUTS[name])
        _same_track(converted, PoseTrack(*arrays, 30.0, (640, 480), name))
