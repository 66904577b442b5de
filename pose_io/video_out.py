"""Frames out: H.264 mp4 written atomically from a stream of frames, and pose tracks drawn as videos
(reading: :mod:`pose_io.video`).

Frames are uint8 RGB ``[H, W, 3]`` arrays, written one at a time, so a long video never sits in memory; the
encoder is imageio-ffmpeg's bundled ffmpeg, imported only when a video is actually written.
"""

from __future__ import annotations

import contextlib
import logging
import os
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING

import cv2
import numpy as np

from pose_io.atomic import atomic_file
from pose_io.draw import blank_canvas, draw_pose
from pose_io.errors import InputError
from pose_io.limits import check_fps, check_image_size
from pose_io.track import PoseTrack
from pose_io.video import Frames

if TYPE_CHECKING:
    from typing_extensions import Self

log = logging.getLogger(__name__)


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
        audio: a file whose sound the video gets, from its start, cut to the video's length
            (:func:`pose_io.audio.mux_audio`); None: silent.
    """

    def __init__(self, path: str | os.PathLike, fps: float, overwrite: bool = False, crf: int = 18,
                 audio: str | os.PathLike | None = None) -> None:
        self.path = Path(path)
        self.audio = Path(audio) if audio is not None else None
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
            if exc_type is None and self.audio is not None:
                from pose_io.audio import mux_audio

                mux_audio(self._tmp, self.audio, self.frames_written / self.fps)  # type: ignore[arg-type]
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
