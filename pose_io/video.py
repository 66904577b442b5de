"""Frames in and out: reading a video file or an image folder as a stream, writing H.264 mp4.

Everything streams one frame at a time, so a long video never sits in memory. Frames are uint8 RGB
``[H, W, 3]`` arrays. Video files are decoded with imageio-ffmpeg (its bundled ffmpeg binary), image
folders with OpenCV. imageio-ffmpeg is imported only when a video is actually read or written.
"""

from __future__ import annotations

import contextlib
import logging
import os
import re
import warnings
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING

import cv2
import numpy as np

from pose_io.atomic import atomic_file
from pose_io.draw import blank_canvas, draw_pose
from pose_io.errors import InputError
from pose_io.limits import MAX_FPS, MIN_FPS, check_fps, check_image_size
from pose_io.track import PoseTrack

if TYPE_CHECKING:
    from typing_extensions import Self

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

    @property
    def num_frames(self) -> int:
        """Number of frames; for a video, counted by decoding it once (cached)."""
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

    def _video_frames(self) -> Iterator[np.ndarray]:
        w, h = self.size
        gen, _meta = _ffmpeg_reader(self.path)
        try:
            for raw in gen:
                yield np.frombuffer(raw, dtype=np.uint8).reshape(h, w, 3).copy()  # [H, W, 3]
        finally:
            gen.close()


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
    except ImportError:  # Pillow comes with matplotlib and scikit-image; without it OpenCV's own cap holds
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


def _ffmpeg_reader(path: Path, attempts: int = 3) -> tuple[Iterator[bytes], dict]:
    """imageio-ffmpeg's frame generator and the video's metadata.

    imageio-ffmpeg reads the metadata from ffmpeg's log in a thread; on a busy machine a very short video can
    finish before that thread has seen the header ("Could not load meta information"). Opening again works.
    """
    import imageio_ffmpeg

    for attempt in range(attempts):
        gen = imageio_ffmpeg.read_frames(str(path), pix_fmt="rgb24")
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
        raise InputError(f"{path}: cannot read as a video ({_first_line(exc)})") from None
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
    if not MIN_FPS <= stored <= MAX_FPS:  # none stored, or a broken time base
        if fps is None:
            log.warning("%s: no usable frame rate stored (%g); assuming %g fps", path, stored, DEFAULT_FPS)
        stored = 0.0
    return Frames(path, "video", fps or (stored if stored > 0 else DEFAULT_FPS), size)  # type: ignore[arg-type]


class VideoWriter:
    """Write uint8 RGB frames to an H.264 (yuv420p) mp4, atomically.

    The file appears at ``path`` only when the ``with`` block ends without an error and at least one
    frame was written. yuv420p needs even sizes: an odd width or height is padded by repeating the last
    column or row. All frames must have the first frame's size.

    Example::

        with VideoWriter("out.mp4", fps=30) as video:
            for frame in frames:
                video.write(frame)

    Args:
        path: output ``.mp4`` path.
        fps: frame rate.
        overwrite: replace an existing file; otherwise an existing ``path`` is an InputError.
        crf: x264 constant rate factor (0 lossless .. 51 worst; 18 is visually lossless).
    """

    def __init__(self, path: str | os.PathLike, fps: float, overwrite: bool = False, crf: int = 18) -> None:
        self.path = Path(path)
        self.fps = check_fps(fps, f"{self.path}: fps")
        self.crf = int(crf)
        self.overwrite = overwrite
        self.frames_written = 0
        self.size: tuple[int, int] | None = None
        self._stack = contextlib.ExitStack()
        self._tmp: Path | None = None
        self._gen = None

    def __enter__(self) -> Self:
        self._tmp = self._stack.enter_context(atomic_file(self.path, overwrite=self.overwrite))
        return self

    def write(self, frame: np.ndarray) -> None:
        """Append one [H, W, 3] uint8 RGB frame."""
        if self._tmp is None:
            raise RuntimeError("VideoWriter.write outside its with block")
        if frame.dtype != np.uint8 or frame.ndim != 3 or frame.shape[2] != 3:
            raise InputError(f"{self.path}: frames must be [H, W, 3] uint8, got {frame.dtype} {frame.shape}")
        size = (frame.shape[1], frame.shape[0])
        if self._gen is None:
            self._start(size)
        elif size != self.size:
            raise InputError(f"{self.path}: frame {self.frames_written} is {size[0]}x{size[1]}, "
                             f"earlier frames are {self.size[0]}x{self.size[1]}")  # type: ignore[index]
        h, w = frame.shape[:2]
        if w % 2 or h % 2:
            frame = np.pad(frame, ((0, h % 2), (0, w % 2), (0, 0)), mode="edge")
        self._gen.send(np.ascontiguousarray(frame))  # type: ignore[union-attr]
        self.frames_written += 1

    def _start(self, size: tuple[int, int]) -> None:
        import imageio_ffmpeg

        self.size = size
        even = (size[0] + size[0] % 2, size[1] + size[1] % 2)
        self._gen = imageio_ffmpeg.write_frames(
            str(self._tmp), even, fps=self.fps, codec="libx264", pix_fmt_in="rgb24", pix_fmt_out="yuv420p",
            quality=None, macro_block_size=1, ffmpeg_log_level="error",
            output_params=["-crf", str(self.crf), "-preset", "medium", "-movflags", "+faststart"],
        )
        self._gen.send(None)  # start ffmpeg

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        try:
            if self._gen is not None:
                self._gen.close()  # waits for ffmpeg to finish the file
            if exc_type is None and self.frames_written == 0:
                raise InputError(f"{self.path}: no frames to write")
        except BaseException as err:
            self._stack.__exit__(type(err), err, err.__traceback__)
            raise
        self._stack.__exit__(exc_type, exc, tb)


def render_track_frames(
    track: PoseTrack,
    size: tuple[int, int] | None = None,
    background: Iterable[np.ndarray] | None = None,
    thickness: int | None = None,
) -> Iterator[np.ndarray]:
    """Draw each frame of ``track`` over black or over background frames.

    Args:
        track: the poses; coordinates are scaled from ``track.image_size`` to ``size``.
        size: (width, height) of the output frames; default ``track.image_size``.
        background: frames to draw on (resized to ``size`` when they differ); when they run out
            before the track does, the remaining frames are drawn over black.
        thickness: limb width in pixels (default: scales with the frame, see ``draw_pose``).

    Yields:
        [H, W, 3] uint8 RGB frames, one per track frame.
    """
    w, h = check_image_size(size, "drawing size") if size is not None else track.image_size
    scale = np.array([w / track.image_size[0], h / track.image_size[1]], dtype=np.float32)
    layout = track.joint_layout
    frames = iter(background) if background is not None else None
    for t in range(track.num_frames):
        canvas = None
        if frames is not None:
            canvas = next(frames, None)
            if canvas is None:
                log.warning("background has fewer frames than the track (%d); drawing the rest over black", t)
                frames = None
            elif (canvas.shape[1], canvas.shape[0]) != (w, h):
                canvas = cv2.resize(canvas, (w, h), interpolation=cv2.INTER_AREA)
            elif not canvas.flags.writeable:
                canvas = canvas.copy()
        if canvas is None:
            canvas = blank_canvas(w, h)
        yield draw_pose(canvas, track.joints[t] * scale, layout, thickness=thickness)


def write_pose_video(
    track: PoseTrack,
    path: str | os.PathLike,
    background: Frames | None = None,
    overwrite: bool = False,
    progress: Callable[[int, int], None] | None = None,
) -> Path:
    """Render ``track`` as an mp4 at the track's fps, over black or over ``background``'s frames.

    Args:
        track: the poses.
        path: output ``.mp4``.
        background: frames to draw on; the output then has their size (poses are scaled to it).
        overwrite: replace an existing file.
        progress: called as ``progress(done, total)`` after each frame.

    Returns:
        ``path``.
    """
    size = background.size if background is not None else track.image_size
    with VideoWriter(path, track.fps, overwrite=overwrite) as video:
        for t, frame in enumerate(render_track_frames(track, size=size, background=background)):
            video.write(frame)
            if progress is not None:
                progress(t + 1, track.num_frames)
    return Path(path)
