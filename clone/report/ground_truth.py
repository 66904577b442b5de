"""The ground truth of a report: the reference really performing the driver's motion, read and checked.

Both readers check the ground truth against the driver's length and the reference model's frame size
before any slow work, so a mismatch ends with one clear line.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Iterator
from typing import TYPE_CHECKING

import numpy as np

from clone.model.canvas import Canvas, cut_frame
from pose_io.errors import InputError
from pose_io.track import PoseTrack

if TYPE_CHECKING:
    from pose_io.video import Frames


def read_gt_poses(path: str | os.PathLike, num_frames: int, image_size: tuple[int, int]) -> PoseTrack:
    """Ground-truth poses as body15, checked against the driver's length and the reference's frame size.

    Args:
        path: any pose file or folder ``pose_io`` reads.
        num_frames: the driver's frame count.
        image_size: (width, height) of the reference's frames; used when the file stores no size.

    Raises:
        InputError: a different number of frames, or a stored size that differs from ``image_size``.
    """
    from pose_io.readers import read_track_summary

    summary = read_track_summary(path, fallback_size=image_size)
    track = summary.track
    if len(track) != num_frames:
        raise InputError(f"{path}: ground-truth poses have {len(track)} frames, the driver has {num_frames}")
    if track.image_size != tuple(image_size):
        if summary.size_source in ("file", "given"):
            raise InputError(
                f"{path}: ground-truth poses are for {track.image_size[0]}x{track.image_size[1]} frames, "
                f"the reference model's frames are {image_size[0]}x{image_size[1]}"
            )
        track = track.replace(image_size=image_size)  # the file stores no size: the reference's is meant
    return track.to_layout("body15")


def open_gt_frames(path: str | os.PathLike, num_frames: int, image_size: tuple[int, int]) -> Frames:
    """Ground-truth frames (video or image folder), checked against the driver's length and the reference's size.

    Args:
        path: a video or a folder of images.
        num_frames: the driver's frame count.
        image_size: (width, height) of the reference's frames.

    Returns:
        A re-iterable ``pose_io.video.Frames``.

    Raises:
        InputError: unreadable, a different number of frames, or a frame size other than ``image_size``.
    """
    from pose_io.video import read_frames

    frames = read_frames(path)
    if tuple(frames.size) != tuple(image_size):
        raise InputError(
            f"{path}: ground-truth frames are {frames.size[0]}x{frames.size[1]}, the reference model's frames "
            f"are {image_size[0]}x{image_size[1]}"
        )
    if frames.num_frames != num_frames:
        raise InputError(
            f"{path}: {frames.num_frames} ground-truth frames, the driver has {num_frames} frames"
        )
    return frames


def cut_gt_frames(
    frames: Iterable[np.ndarray], source: str | os.PathLike, num_frames: int, canvas: Canvas
) -> Iterator[np.ndarray]:
    """The ground-truth frames as the generator sees them: each cut to the reference model's canvas.

    Args:
        frames: [H, W, 3] uint8 RGB full frames, e.g. those of ``open_gt_frames``.
        source: where they were read from, for the error message.
        num_frames: frames to yield.
        canvas: the reference model's canvas.

    Yields:
        [S, S, 3] uint8 RGB, one per frame.

    Raises:
        InputError: ``frames`` ends before ``num_frames`` (a video may hold fewer frames than it says).
    """
    stream = iter(frames)
    for t in range(num_frames):
        full = next(stream, None)
        if full is None:
            raise InputError(f"{source}: ran out of frames at frame {t} of {num_frames}")
        yield cut_frame(full, canvas)
