"""Small media files for tests: a WAV tone and a video of a real person (skimage's astronaut), with or without sound."""

from __future__ import annotations

import wave
from pathlib import Path

import numpy as np
import pytest

from pose_io.video_out import VideoWriter


def write_tone(path: Path, seconds: float, rate: int = 22050) -> Path:
    """A mono 440 Hz tone of ``seconds`` as 16-bit WAV."""
    t = np.arange(int(seconds * rate)) / rate
    samples = (0.3 * 32767 * np.sin(2 * np.pi * 440 * t)).astype("<i2")
    with wave.open(str(path), "wb") as out:
        out.setnchannels(1)
        out.setsampwidth(2)
        out.setframerate(rate)
        out.writeframes(samples.tobytes())
    return path


def write_person_video(path: Path, frames: int, fps: float = 12.0, audio: Path | None = None, size: int = 256) -> Path:
    """``frames`` frames of the astronaut (a real person MediaPipe finds), shifted a little each frame."""
    import cv2

    skimage_data = pytest.importorskip("skimage.data")
    image = cv2.resize(skimage_data.astronaut(), (size, size), interpolation=cv2.INTER_AREA)
    with VideoWriter(path, fps=fps, audio=audio) as video:
        for t in range(frames):
            video.write(np.roll(image, t, axis=1))
    return path


def write_grey_video(path: Path, frames: int = 2, fps: float = 10.0) -> Path:
    """``frames`` flat grey 64x64 frames: a video with nobody in it."""
    with VideoWriter(path, fps=fps) as video:
        for _ in range(frames):
            video.write(np.full((64, 64, 3), 128, np.uint8))
    return path


def media_info(path: Path) -> tuple[bool, float]:
    """(has an audio stream, the file's duration in seconds) as ffmpeg reads them."""
    import re
    import subprocess

    import imageio_ffmpeg

    err = subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-hide_banner", "-i", str(path)], capture_output=True,
                         text=True, check=False).stderr
    h, m, s = re.search(r"Duration: (\d+):(\d+):([\d.]+)", err).groups()
    return " Audio: " in err, int(h) * 3600 + int(m) * 60 + float(s)
