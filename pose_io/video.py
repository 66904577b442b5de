"""Frames in: reading a video file or an image folder as a stream (writing: :mod:`pose_io.video_out`).

Everything streams one frame at a time, so a long video never sits in memory. Frames are uint8 RGB
``[H, W, 3]`` arrays. Video files are decoded with imageio-ffmpeg (its bundled ffmpeg binary), image
folders with OpenCV. imageio-ffmpeg is imported only when a video is actually read.
"""

from __future__ import annotations

import logging
import os
import re
import warnings
from collections.abc import Iterator
from pathlib import Path

import cv2
import numpy as np

from pose_io.errors import InputError, raise_if_interrupted
from pose_io.limits import MAX_FPS, MIN_FPS, check_fps, check_image_size

log = logging.getLogger(__name__)

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp")
DEFAULT_FPS = 30.0
_DIGITS = re.compile(r"(\d+)")


def natural_key(name: str) -> tuple:
    """Sort key ordering embedded numbers by value: ``frame_2`` before ``frame_10``."""
    return tuple(int(p) if p.isdigit() else p.lower() for p in _DIGITS.split(name))


def image_files(folder: Path) -> list[Path]:
    """The image files of ``folder`` (by suffix, hidden files skipped) in natural number order."""
    files = [p for p in folder.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES and not p.name.startswith(".")]
    return sorted(files, key=lambda p: natural_key(p.name))


class Frames:
    """A re-iterable stream of uint8 RGB frames from a video file, an image folder or one image.

    Each ``for frame in frames`` decodes from the start again; each frame is a fresh writable
    ``[H, W, 3]`` uint8 array. Create it with :func:`read_frames`, which checks that the first frame
    can be decoded.

    Attributes:
        path: the source.
        kind: ``"video"``, ``"images"`` (a folder) or ``"image"`` (one file).
        fps: frames per second (the video's; for images the value given, default 30).
        size: (width, height) of every frame.
    """

    def __init__(self, path: Path, kind: str, fps: float, size: tuple[int, int],
                 files: tuple[Path, ...] = (), count: int | None = None) -> None:
        self.path = path
        self.kind = kind
        self.fps = fps
        self.size = size
        self._files = files
        self._count = count
        # A variable-frame-rate video (a phone's) decodes at its nominal rate, frames repeated where the camera
        # paused: ``fps`` is that rate and the count is what decoding gives, not the frames stored.
        self.variable_rate = False

    @property
    def num_frames(self) -> int:
        """Number of frames; for a video, counted by decoding it once (cached)."""
        if self._count is None and self.variable_rate:
            self._count = sum(1 for _ in self._raw_frames())  # as decoded: at the constant rate of ``fps``
        if self._count is None:
            import imageio_ffmpeg

            try:
                self._count = int(imageio_ffmpeg.count_frames_and_secs(str(self.path))[0])
            except (OSError, RuntimeError) as exc:
                raise InputError(f"{self.path}: cannot count video frames ({_first_line(exc)})") from None
        return self._count

    def __len__(self) -> int:
        return self.num_frames

    def __iter__(self) -> Iterator[np.ndarray]:
        if self.kind == "video":
            return self._video_frames()
        return (self._image(f) for f in self._files)

    def _image(self, path: Path) -> np.ndarray:
        frame = _read_image(path)
        if (frame.shape[1], frame.shape[0]) != self.size:
            raise InputError(
                f"{path}: image is {frame.shape[1]}x{frame.shape[0]}, earlier frames are {self.size[0]}x{self.size[1]}"
            )
        return frame

    def _raw_frames(self) -> Iterator[bytes]:
        # Constant rate: every stored frame once, as the count has it (a file cut short included); variable
        # rate: ffmpeg's constant-rate output at ``fps``.
        gen, _meta = _ffmpeg_reader(self.path, [] if self.variable_rate else ["-fps_mode", "passthrough"])
        try:
            yield from gen
        finally:
            gen.close()

    def _video_frames(self) -> Iterator[np.ndarray]:
        w, h = self.size
        for raw in self._raw_frames():
            yield np.frombuffer(raw, dtype=np.uint8).reshape(h, w, 3).copy()  # [H, W, 3]


def ffmpeg_probe(path: str | os.PathLike) -> str | None:
    """What the bundled ffmpeg says of ``path``'s streams (its ``-i`` report), or None when it cannot run."""
    import subprocess

    import imageio_ffmpeg

    try:
        return subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-hide_banner", "-nostdin", "-i", str(path)],
                              capture_output=True, text=True, errors="replace", timeout=120, check=False).stderr
    except (OSError, subprocess.TimeoutExpired):
        return None


def _why_unreadable(path: Path, exc: BaseException) -> str:
    """Why ffmpeg could not open ``path`` as a video, in words: no video stream (a sound file), damaged or cut
    short, else ffmpeg's own first line."""
    probe = ffmpeg_probe(path)
    if probe is None:
        return _first_line(exc)
    if " Audio: " in probe and " Video: " not in probe:
        return "it has sound but no video stream"
    if "moov atom not found" in probe or "Invalid data found" in probe or "End of file" in probe:
        return "damaged or cut short: ffmpeg finds no readable video in it"
    return _first_line(exc)


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    return text.splitlines()[0][:160] if text else exc.__class__.__name__


def _header_size(path: Path) -> tuple[int, int] | None:
    """(width, height) from an image file's header without decoding it, or None when Pillow cannot tell.

    Raises:
        InputError: an image so large that Pillow refuses it as a decompression bomb (over ~179M pixels).
    """
    try:
        from PIL import Image
    except ImportError as exc:  # Pillow comes with matplotlib and scikit-image; without it OpenCV's own cap holds
        raise_if_interrupted(exc)
        return None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)  # our limit decides, not Pillow's
            with Image.open(path) as image:
                return image.size
    except Image.DecompressionBombError as exc:
        raise InputError(f"{path}: image too large to decode ({_first_line(exc)})") from None
    except (OSError, ValueError, SyntaxError, EOFError):  # not an image Pillow knows: OpenCV will say
        return None


def _read_image(path: Path) -> np.ndarray:
    """One image file as [H, W, 3] uint8 RGB; its size is checked from the header before decoding."""
    size = _header_size(path) if path.is_file() else None
    if size is not None:
        check_image_size(size, f"{path}: image size")
    data = np.fromfile(path, dtype=np.uint8) if path.is_file() else None
    bgr = cv2.imdecode(data, cv2.IMREAD_COLOR) if data is not None and data.size else None
    if bgr is None:
        raise InputError(f"{path}: cannot read as an image")
    return cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)


def read_frames(path: str | os.PathLike, fps: float | None = None) -> Frames:
    """Open a video file, an image folder (natural number order) or a single image as a frame stream.

    Args:
        path: the source.
        fps: frame rate for image folders (default 30); for a video it overrides the stored rate.

    Returns:
        A :class:`Frames` whose first frame is known to decode.

    Raises:
        InputError: missing path, empty folder, or a file that cannot be decoded.
    """
    path = Path(path)
    if not path.exists():
        raise InputError(f"{path}: does not exist")
    if fps is not None:
        fps = check_fps(fps, "fps")
    if path.is_dir():
        files = image_files(path)
        if not files:
            raise InputError(f"{path}: no image files ({', '.join(IMAGE_SUFFIXES)})")
        first = _read_image(files[0])
        size = (first.shape[1], first.shape[0])
        return Frames(path, "images", fps or DEFAULT_FPS, size, tuple(files), len(files))
    if path.suffix.lower() in IMAGE_SUFFIXES:
        first = _read_image(path)
        return Frames(path, "image", fps or DEFAULT_FPS, (first.shape[1], first.shape[0]), (path,), 1)
    return _open_video(path, fps)


def _ffmpeg_reader(path: Path, output_params: list[str] | None = None, attempts: int = 3
                   ) -> tuple[Iterator[bytes], dict]:
    """imageio-ffmpeg's frame generator and the video's metadata.

    imageio-ffmpeg reads the metadata from ffmpeg's log in a thread; on a busy machine a very short video can
    finish before that thread has seen the header ("Could not load meta information"). Opening again works.
    """
    import imageio_ffmpeg

    for attempt in range(attempts):
        gen = imageio_ffmpeg.read_frames(str(path), pix_fmt="rgb24", output_params=output_params)
        try:
            return gen, next(gen)
        except OSError as exc:
            gen.close()
            if "meta information" not in str(exc) or attempt == attempts - 1:
                raise
    raise AssertionError("unreachable")


def _open_video(path: Path, fps: float | None) -> Frames:
    try:
        gen, meta = _ffmpeg_reader(path)
    except StopIteration:
        raise InputError(f"{path}: video has no frames") from None
    except (OSError, RuntimeError, ValueError) as exc:
        raise InputError(f"{path}: cannot read as a video ({_why_unreadable(path, exc)})") from None
    try:
        check_image_size(tuple(meta.get("size") or ()), f"{path}: video size")  # before a frame is decoded
    except InputError:
        gen.close()
        raise
    try:
        next(gen)  # the first frame must decode
    except StopIteration:
        raise InputError(f"{path}: video has no frames") from None
    except (OSError, RuntimeError, ValueError) as exc:
        raise InputError(f"{path}: cannot read as a video ({_first_line(exc)})") from None
    finally:
        gen.close()
    size = tuple(int(v) for v in meta["size"])
    stored = float(meta.get("fps") or 0.0)
    nominal = _nominal_rate(path)
    variable = nominal is not None and MIN_FPS <= nominal <= MAX_FPS and abs(nominal - stored) > 0.01 * nominal
    if variable:
        log.info("%s: variable frame rate (%g fps on average); read at its nominal %g fps", path, stored, nominal)
        stored = float(nominal)
    if not MIN_FPS <= stored <= MAX_FPS:  # none stored, or a broken time base
        if fps is None:
            log.warning("%s: no usable frame rate stored (%g); assuming %g fps", path, stored, DEFAULT_FPS)
        stored = 0.0
    frames = Frames(path, "video", fps or (stored if stored > 0 else DEFAULT_FPS), size)  # type: ignore[arg-type]
    frames.variable_rate = variable
    return frames


_RATES = re.compile(r"Stream #\d+:\d+.*?: Video: .*?(?:, ([\d.]+) fps)?, ([\d.]+)(k?) tbr")


def _nominal_rate(path: Path) -> float | None:
    """The video stream's nominal rate (ffmpeg's ``tbr``: the rate it decodes at), or None when not stated."""
    match = _RATES.search(ffmpeg_probe(path) or "")
    if match is None:
        return None
    return float(match.group(2)) * (1000.0 if match.group(3) else 1.0)


class _RotationNotice(logging.Filter):
    """imageio-ffmpeg warns that a rotated video's frames differ in size from the stored ones: that is the
    rotation applied as it should be, not news for the user."""

    def filter(self, record: logging.LogRecord) -> bool:
        return "is different from the source frame size" not in record.getMessage()


logging.getLogger("imageio_ffmpeg").addFilter(_RotationNotice())
