"""Ground truth for a report: read, checked against the driver and the reference, cut to the canvas."""

from __future__ import annotations

import numpy as np
import pytest

from clone.model.canvas import full_frame_canvas
from clone.report.ground_truth import cut_gt_frames, open_gt_frames, read_gt_poses
from pose_io import InputError
from tests.clone.report.helpers import SIZE, walk, write_gt


def test_ground_truth_that_fits(tmp_path):
    poses, frames = write_gt(tmp_path, frames=5)
    track = read_gt_poses(poses, 5, (SIZE, SIZE))
    assert track.layout == "body15" and track.image_size == (SIZE, SIZE)
    np.testing.assert_allclose(track.joints, walk(5).joints, atol=1e-3)
    opened = open_gt_frames(frames, 5, (SIZE, SIZE))
    assert opened.num_frames == 5 and tuple(opened.size) == (SIZE, SIZE)

    cut = list(cut_gt_frames(opened, frames, 5, full_frame_canvas((SIZE, SIZE), 32)))
    assert len(cut) == 5 and all(c.shape == (32, 32, 3) and c.dtype == np.uint8 for c in cut)


def test_ground_truth_that_does_not_fit(tmp_path):
    poses, frames = write_gt(tmp_path, frames=5)
    with pytest.raises(InputError, match="have 5 frames, the driver has 6"):
        read_gt_poses(poses, 6, (SIZE, SIZE))
    with pytest.raises(
        InputError, match=f"poses are for {SIZE}x{SIZE} frames, the reference model's frames are 80x80"
    ):
        read_gt_poses(poses, 5, (80, 80))
    with pytest.raises(InputError, match="5 ground-truth frames, the driver has 6"):
        open_gt_frames(frames, 6, (SIZE, SIZE))
    with pytest.raises(InputError, match=f"frames are {SIZE}x{SIZE}, the reference model's frames are 80x80"):
        open_gt_frames(frames, 5, (80, 80))

    short = cut_gt_frames(
        [np.zeros((SIZE, SIZE, 3), np.uint8)] * 2, "gt.mp4", 3, full_frame_canvas((SIZE, SIZE), 32)
    )
    with pytest.raises(InputError, match="gt.mp4: ran out of frames at frame 2 of 3"):
        list(short)
