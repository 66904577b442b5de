"""Sound for the videos we write: whether a file has an audio stream, and muxing one into a finished mp4.

The driver's music belongs in the clip made from it: `clone drive DRIVER.mp4` gives the output the driver's sound
from the same start, cut to the output's length (the output's frame t is the driver's frame t, at the driver's
fps). Both steps use imageio-ffmpeg's bundled ffmpeg; the video stream is copied, the sound encoded as AAC.
"""

from __future__ import annotations

import os
import re
import subprocess
import tempfile
from pathlib import Path

from pose_io.errors import InputError

AUTO, NONE = "auto", "none"
_AUDIO_STREAM = re.compile(r"^\s*Stream #\d+:\d+.*: Audio: ", re.MULTILINE)


def _ffmpeg() -> str:
    import imageio_ffmpeg

    return imageio_ffmpeg.get_ffmpeg_exe()


def has_audio(path: str | os.PathLike) -> bool:
    """Whether ffmpeg finds an audio stream in ``path`` (False for files it cannot read at all)."""
    from pose_io.video import ffmpeg_probe

    path = Path(path)
    return path.is_file() and bool(_AUDIO_STREAM.search(ffmpeg_probe(path) or ""))


def resolve_audio(audio: str | os.PathLike | None, driver: str | os.PathLike) -> Path | None:
    """The file whose sound the output gets: ``auto`` (the default) the driver's own when it is a video with
    sound, ``none``/None no sound, else the given file, which must have an audio stream."""
    from pose_io.video_poses import is_video

    if audio is None or str(audio) == NONE:
        return None
    if str(audio) == AUTO:
        return Path(driver) if is_video(driver) and has_audio(driver) else None
    path = Path(audio)
    if not path.is_file():
        raise InputError(f"--audio {path}: no such file")
    if not has_audio(path):
        raise InputError(f"--audio {path}: has no audio stream ffmpeg can read")
    return path


def mux_audio(video: Path, audio: Path, duration: float) -> None:
    """Give the finished ``video`` (an mp4, replaced in place) the sound of ``audio`` from its start, cut at
    ``duration`` seconds (the video's length); a shorter sound leaves the rest silent.

    Raises:
        InputError: ffmpeg could not mux (its last line of error output in the message).
    """
    fd, tmp = tempfile.mkstemp(prefix=f".{video.name}.", suffix=".audio.mp4", dir=video.parent)
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        run = subprocess.run(
            [_ffmpeg(), "-hide_banner", "-nostdin", "-v", "error", "-y", "-i", str(video), "-i", str(audio),
             "-map", "0:v:0", "-map", "1:a:0", "-c:v", "copy", "-c:a", "aac", "-b:a", "192k",
             "-t", f"{duration:.6f}", "-movflags", "+faststart", str(tmp_path)],
            capture_output=True, text=True, errors="replace", timeout=3600, check=False)
        if run.returncode != 0:
            last = (run.stderr.strip().splitlines() or ["unknown error"])[-1]
            raise InputError(f"cannot add the sound of {audio} to {video.name}: {last}")
        os.replace(tmp_path, video)
    finally:
        if tmp_path.exists():
            tmp_path.unlink()
