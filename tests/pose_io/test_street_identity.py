"""Several people: on the crowded street of ../shared/real the person followed by extraction stays the same person
through every crossing (identity switches counted: 0)."""

from __future__ import annotations

import numpy as np
import pytest

from pose_io.readers import read_track

pytest.importorskip("mediapipe")


def identity_switches(joints: np.ndarray, jump: float = 0.5) -> int:
    """Steps of the trunk's centre by more than ``jump`` trunk lengths between frames, after a 5-frame running
    median (a one- or two-frame glitch that comes back is not a change of person); [T, 15, 2] body15 joints."""
    from scipy.ndimage import median_filter

    centre = (joints[:, 1] + joints[:, 8]) / 2  # neck and mid-hip
    centre = median_filter(centre, size=(5, 1), mode="nearest")
    trunk = float(np.nanmedian(np.linalg.norm(joints[:, 1] - joints[:, 8], axis=-1)))
    step = np.linalg.norm(np.diff(centre, axis=0), axis=-1) / trunk
    with np.errstate(invalid="ignore"):
        return int(np.sum(step > jump))


def test_identity_switches_counts_a_real_switch():
    joints = np.zeros((10, 15, 2), np.float32)
    joints[:, 1] = (100, 100)
    joints[:, 8] = (100, 200)
    glitch = joints.copy()
    glitch[4, :, 0] += 80  # one frame off, then back
    assert identity_switches(glitch) == 0
    switched = joints.copy()
    switched[5:, :, 0] += 300  # someone else from frame 5 on
    assert identity_switches(switched) == 1


def test_the_street_walker_is_followed_throughout(shared_dir, tmp_path, monkeypatch):
    monkeypatch.setenv("CLONE2D_CACHE", str(tmp_path / "cache"))
    track = read_track(shared_dir / "real" / "street_openpose.avi").to_layout("body15")
    assert track.num_frames == 205 and track.fps == 50.0
    assert (~track.missing[:, [1, 8]]).all()  # neck and mid-hip found in every frame
    assert identity_switches(track.joints) == 0
