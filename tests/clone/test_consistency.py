"""Pose consistency: MediaPipe on frames against the poses they were asked to show."""

from __future__ import annotations

import numpy as np
import pytest

from clone.metrics.consistency import detected_poses, pose_consistency

pytest.importorskip("mediapipe")


def astronaut_frames(n: int) -> list[np.ndarray]:
    skimage_data = pytest.importorskip("skimage.data")
    return [skimage_data.astronaut() for _ in range(n)]  # [512, 512, 3]: a real person, upper body


def test_frames_agree_with_their_own_poses_and_not_with_moved_ones():
    frames = astronaut_frames(3)
    found = detected_poses(frames).joints  # [3, 15, 2]
    assert np.isfinite(found[:, 1]).all()  # the neck is found
    same = pose_consistency(frames, found)
    assert same["pck_0.1"] == 1.0 and same["median_error_pct"] < 1 and same["found_share"] == 1.0
    moved = found.copy()
    moved[..., 0] += 200  # asked to stand 200 px to the right
    off = pose_consistency(frames, moved)
    assert off["pck_0.1"] < 0.2 and off["median_error_pct"] > same["median_error_pct"]


def test_a_frame_without_a_person_misses_every_joint():
    frames = astronaut_frames(1) + [np.full((512, 512, 3), 128, np.uint8)]
    found = detected_poses(frames[:1]).joints
    asked = np.concatenate([found, found])
    result = pose_consistency(frames, asked)
    assert result["found_share"] == 0.5 and result["pck_0.1"] <= 0.5 + 1e-9


def test_the_meter_measures_frame_by_frame_as_the_whole_list_does():
    from clone.metrics.consistency import ConsistencyMeter

    frames = astronaut_frames(3)
    found = detected_poses(frames).joints
    moved = found.copy()
    moved[1:, :, 0] += 200
    with ConsistencyMeter() as meter:
        for frame, asked in zip(frames, moved):
            meter.add(frame, asked)
    assert meter.scores() == pose_consistency(frames, moved)
    with ConsistencyMeter() as empty:
        assert np.isnan(empty.scores()["pck_0.1"])
