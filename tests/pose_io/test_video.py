"""pose_io.video: videos and image folders read as frame streams (written by pose_io.video_out and read back)."""

import cv2
import numpy as np
import pytest

from pose_io import InputError
from pose_io.video import natural_key, read_frames
from pose_io.video_out import VideoWriter


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
