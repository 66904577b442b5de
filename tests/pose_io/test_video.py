import cv2
import numpy as np
import pytest

from pose_io import InputError
from pose_io.video import VideoWriter, natural_key, read_frames, render_track_frames, write_pose_video


def gradient_frames(n: int, w: int = 64, h: int = 48) -> list[np.ndarray]:
    """Smooth frames (compress well, so decoded pixels stay close) that differ per frame."""
    y, x = np.mgrid[0:h, 0:w]
    return [np.stack([x * 3 % 256, y * 4 % 256, np.full_like(x, 20 * i)], axis=-1).astype(np.uint8)
            for i in range(n)]


def test_mp4_round_trip(tmp_path):
    frames = gradient_frames(6)
    with VideoWriter(tmp_path / "a.mp4", fps=25) as video:
        for f in frames:
            video.write(f)
    source = read_frames(tmp_path / "a.mp4")
    assert source.kind == "video" and source.fps == 25.0 and source.size == (64, 48) and len(source) == 6
    decoded = list(source)
    assert len(decoded) == 6 and decoded[0].dtype == np.uint8 and decoded[0].flags.writeable
    for a, b in zip(decoded, frames):
        assert np.abs(a.astype(int) - b).mean() < 4.0
    assert len(list(source)) == 6, "a Frames object can be iterated again"


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


def test_image_folder_in_number_order(tmp_path):
    frames = gradient_frames(11)
    for i, f in enumerate(frames):
        cv2.imwrite(str(tmp_path / f"frame_{i}.png"), cv2.cvtColor(f, cv2.COLOR_RGB2BGR))
    (tmp_path / "notes.txt").write_text("ignored")
    source = read_frames(tmp_path, fps=12)
    assert source.kind == "images" and len(source) == 11 and source.fps == 12 and source.size == (64, 48)
    for got, want in zip(source, frames):
        np.testing.assert_array_equal(got, want)  # PNG is lossless; frame_10 comes last
    assert sorted(["f10", "f9", "f1"], key=natural_key) == ["f1", "f9", "f10"]


def test_bad_sources(tmp_path):
    with pytest.raises(InputError, match="does not exist"):
        read_frames(tmp_path / "none.mp4")
    (tmp_path / "bad.mp4").write_text("not a video")
    with pytest.raises(InputError, match="bad.mp4: cannot read as a video"):
        read_frames(tmp_path / "bad.mp4")
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(InputError, match="no image files"):
        read_frames(empty)
    (empty / "0.png").write_bytes(b"nope")
    with pytest.raises(InputError, match="cannot read as an image"):
        read_frames(empty)
    mixed = tmp_path / "mixed"
    mixed.mkdir()
    cv2.imwrite(str(mixed / "0.png"), np.zeros((8, 8, 3), np.uint8))
    cv2.imwrite(str(mixed / "1.png"), np.zeros((8, 9, 3), np.uint8))
    with pytest.raises(InputError, match="1.png: image is 9x8"):
        list(read_frames(mixed))


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
