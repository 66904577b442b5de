"""pose_io.video_out: the atomic mp4 writer, and pose tracks drawn as frames and videos."""

import numpy as np
import pytest

from pose_io import InputError
from pose_io.video import read_frames
from pose_io.video_out import VideoWriter, render_track_frames, write_pose_video
from tests.pose_io.test_video import gradient_frames


def test_odd_sizes_are_padded_to_even(tmp_path):
    frame = gradient_frames(1, w=33, h=21)[0]
    with VideoWriter(tmp_path / "odd.mp4", fps=10) as video:
        video.write(frame)
    source = read_frames(tmp_path / "odd.mp4")
    assert source.size == (34, 22)
    got = next(iter(source))
    assert np.abs(got[:21, :33].astype(int) - frame).mean() < 4.0


def test_writer_is_atomic_and_checks_input(tmp_path):
    path = tmp_path / "a.mp4"
    with pytest.raises(RuntimeError, match="boom"), VideoWriter(path, fps=10) as video:
        video.write(gradient_frames(1)[0])
        raise RuntimeError("boom")
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(InputError, match="no frames"), VideoWriter(path, fps=10):
        pass
    with pytest.raises(InputError, match="earlier frames are 64x48"), VideoWriter(path, fps=10) as video:
        video.write(gradient_frames(1)[0])
        video.write(gradient_frames(1, w=32)[0])
    with pytest.raises(InputError, match="uint8"), VideoWriter(path, fps=10) as video:
        video.write(np.zeros((4, 4, 3), np.float32))
    assert list(tmp_path.iterdir()) == []
    with VideoWriter(path, fps=10) as video:
        video.write(gradient_frames(1)[0])
    with pytest.raises(InputError, match="already exists"):
        VideoWriter(path, fps=10).__enter__()


def test_render_track_frames_draws_where_the_joints_are(walking_track):
    frames = list(render_track_frames(walking_track.frames(0, 3)))
    assert len(frames) == 3 and frames[0].shape == (480, 640, 3)
    x, y = walking_track.joint("mid_hip")[0].round().astype(int)
    assert frames[0][y, x].max() > 100 and frames[0][5, 5].max() == 0
    half = next(render_track_frames(walking_track, size=(320, 240)))
    assert half.shape == (240, 320, 3) and half[y // 2, x // 2].max() > 100
    background = [np.full((240, 320, 3), 50, np.uint8)]  # runs out after one frame, then black
    over = list(render_track_frames(walking_track.frames(0, 2), background=background))
    assert over[0][5, 5].tolist() == [50, 50, 50] and over[1][5, 5].tolist() == [0, 0, 0]


def test_write_pose_video(tmp_path, walking_track):
    path = write_pose_video(walking_track.frames(0, 4), tmp_path / "p.mp4")
    source = read_frames(path)
    assert len(source) == 4 and source.size == (640, 480) and source.fps == 30.0
