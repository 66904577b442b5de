"""Video files as phones and cameras make them, built with the bundled ffmpeg: each gives the right frames or one
clean error (rotation metadata, variable frame rate, odd sizes, 10-bit, interlaced, cut short, sound only, a
non-ASCII name)."""

from __future__ import annotations

import subprocess
from pathlib import Path

import imageio_ffmpeg
import numpy as np
import pytest
from typer.testing import CliRunner

from clone.cli.main import app
from pose_io.errors import InputError
from pose_io.video import read_frames

SOURCE = ["-f", "lavfi", "-i", "testsrc2=size=320x240:rate=30:duration=2"]


def ffmpeg(*args: str) -> None:
    subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-y", *args], check=True, timeout=120)


@pytest.fixture(scope="module")
def media(tmp_path_factory) -> Path:
    tmp = tmp_path_factory.mktemp("real_files")
    ffmpeg(*SOURCE, "-f", "lavfi", "-i", "sine=frequency=440:duration=2", "-c:v", "libx264", "-pix_fmt", "yuv420p",
           "-c:a", "aac", "-shortest", str(tmp / "plain.mp4"))
    ffmpeg("-display_rotation", "90", "-i", str(tmp / "plain.mp4"), "-c", "copy", str(tmp / "rotated.mp4"))
    # Every third frame kept, at their own times: 11.45 fps on average in a 30 fps time base, as phones write.
    ffmpeg("-i", str(tmp / "plain.mp4"), "-vf", r"select='not(mod(n\,3))+eq(n\,1)'", "-fps_mode", "vfr",
           "-c:v", "libx264", "-an", str(tmp / "variable.mp4"))
    ffmpeg(*SOURCE[:3], "testsrc2=size=322x242:rate=25:duration=1", "-vf", "format=yuv444p,crop=321:241", "-c:v", "ffv1",
           str(tmp / "odd.mkv"))
    ffmpeg(*SOURCE, "-t", "1", "-c:v", "libx264", "-pix_fmt", "yuv420p10le", str(tmp / "ten_bit.mp4"))
    ffmpeg(*SOURCE, "-t", "1", "-c:v", "libx264", "-flags", "+ilme+ildct", "-x264opts", "tff=1", "-pix_fmt",
           "yuv420p", str(tmp / "interlaced.mp4"))
    ffmpeg("-f", "lavfi", "-i", "sine=frequency=440:duration=1", "-c:a", "aac", str(tmp / "sound.m4a"))
    ffmpeg("-i", str(tmp / "plain.mp4"), "-c", "copy", "-movflags", "+faststart", str(tmp / "faststart.mp4"))
    data = (tmp / "faststart.mp4").read_bytes()
    (tmp / "cut_short.mp4").write_bytes(data[: len(data) // 2])  # the index first: the first half still plays
    plain = (tmp / "plain.mp4").read_bytes()
    (tmp / "no_index.mp4").write_bytes(plain[: len(plain) * 2 // 3])  # the index at the end, lost
    (tmp / "çava väri 動画.mp4").write_bytes(plain)
    return tmp


@pytest.mark.parametrize(("name", "fps", "size", "frames"), [
    ("plain.mp4", 30.0, (320, 240), 60),
    ("rotated.mp4", 30.0, (240, 320), 60),  # portrait, as the phone showed it
    ("variable.mp4", 30.0, (320, 240), 58),  # at its nominal rate: frame t at t / 30 s, the clip 2 s long
    ("odd.mkv", 25.0, (321, 241), 25),
    ("ten_bit.mp4", 30.0, (320, 240), 30),
    ("interlaced.mp4", 30.0, (320, 240), 30),
    ("çava väri 動画.mp4", 30.0, (320, 240), 60),
])
def test_the_right_frames(media, name, fps, size, frames):
    video = read_frames(media / name)
    decoded = list(video)
    assert video.fps == pytest.approx(fps) and video.size == size
    assert video.num_frames == len(decoded) == frames
    assert all(f.shape == (size[1], size[0], 3) and f.dtype == np.uint8 for f in decoded)
    assert np.std(decoded[0]) > 10  # a picture, not a blank


def test_a_file_cut_short_gives_what_can_be_read(media):
    video = read_frames(media / "cut_short.mp4")
    assert 10 < len(list(video)) == video.num_frames < 60


@pytest.mark.parametrize(("name", "why"), [
    ("sound.m4a", "it has sound but no video stream"),
    ("no_index.mp4", "damaged or cut short"),
])
def test_one_clean_error(media, name, why):
    with pytest.raises(InputError, match=why):
        read_frames(media / name)
    result = CliRunner().invoke(app, ["pose", "info", str(media / name)])
    lines = [line for line in result.output.splitlines() if line.strip()]
    assert result.exit_code == 2 and len(lines) == 1 and lines[0].startswith("error: ") and why in lines[0]
