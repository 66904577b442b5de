"""A pose track or gap-free values at another frame rate, by linear interpolation in time: one rule for the
frames (:func:`resampled_frames`) and the interpolation, whatever is resampled."""

from __future__ import annotations

import math

import numpy as np

from pose_io.errors import InputError
from pose_io.limits import check_fps, check_frame_count
from pose_io.track import PoseTrack

#: Output frames resampled at once (bounds the float64 temporaries of long resamplings).
_RESAMPLE_CHUNK = 65_536


def resample(track: PoseTrack, fps: float, frames: int | None = None) -> PoseTrack:
    """The track at another frame rate, by linear interpolation in time.

    Output frame ``i`` is at time ``i / fps``; by default frames cover the input's span, from its first
    frame to its last (``floor((T - 1) * fps / track.fps) + 1`` frames). A joint is interpolated between
    the two input frames around that time, and is missing when either of them lacks it (unless the time
    falls on an input frame, which is then copied as it is).

    Args:
        track: the track.
        fps: the new frame rate (0.01 to 1,000, see :mod:`pose_io.limits`).
        frames: the number of output frames instead (>= 1; e.g. to give a track back the frame count it
            had before it was resampled); times past the input's last frame take that frame.

    Returns:
        The resampled track with ``fps`` set.

    Raises:
        InputError: an fps out of range, or more than 1,000,000 output frames (checked before allocating).
    """
    fps = check_fps(fps, "resampling fps")
    ratio = track.fps / fps
    n_out = _output_frames(track.num_frames, track.fps, fps, frames)
    joints = np.empty((n_out, *track.joints.shape[1:]), dtype=np.float32)  # [N, J, 2]
    conf = np.empty((n_out, track.joints.shape[1]), dtype=np.float32)  # [N, J]
    for start in range(0, n_out, _RESAMPLE_CHUNK):  # chunks keep the float64 temporaries small
        stop = min(start + _RESAMPLE_CHUNK, n_out)
        joints[start:stop], conf[start:stop] = _interpolate(track, _sources(start, stop, ratio, track.num_frames))
    return PoseTrack(joints, conf, fps, track.image_size, track.layout)


def resample_values(values: np.ndarray, fps: float, new_fps: float, frames: int | None = None) -> np.ndarray:
    """Gap-free values ``[T, ...]`` (e.g. joints filled by :func:`pose_io.clean.hold_fill`) at another frame rate: the frames
    and the linear interpolation of :func:`resample`, in float64.

    Args:
        values: [T, ...] values at ``fps``, no NaN.
        fps: their frame rate.
        new_fps: the new one (0.01 to 1,000).
        frames: the number of output frames (default: those covering the input's span).

    Returns:
        [T', ...] float64.

    Raises:
        InputError: a rate out of range, or more than 1,000,000 output frames (checked before allocating).
    """
    fps, new_fps = check_fps(fps, "resampling fps"), check_fps(new_fps, "resampling fps")
    n_out = _output_frames(len(values), fps, new_fps, frames)
    out = np.empty((n_out, *values.shape[1:]), dtype=np.float64)
    for start in range(0, n_out, _RESAMPLE_CHUNK):
        stop = min(start + _RESAMPLE_CHUNK, n_out)
        out[start:stop] = _lerp(values, _sources(start, stop, fps / new_fps, len(values)))
    return out


def resampled_frames(n_in: int, fps: float, new_fps: float) -> int:
    """Frames :func:`resample` gives by default: those covering ``n_in`` frames at ``fps`` at ``new_fps``."""
    return math.floor((n_in - 1) * new_fps / fps + 1e-9) + 1


def _output_frames(n_in: int, fps: float, new_fps: float, frames: int | None) -> int:
    """Frames of a resampled track (see :func:`resample`), checked against the frame limit."""
    n_out = resampled_frames(n_in, fps, new_fps) if frames is None else frames
    if not isinstance(n_out, (int, np.integer)) or isinstance(n_out, bool) or n_out < 1:
        raise InputError(f"resampling to {n_out!r} frames: a whole number of at least 1 is needed")
    return check_frame_count(int(n_out), f"resampling {n_in} frames from {fps:g} to {new_fps:g} fps")


def _sources(start: int, stop: int, ratio: float, n_in: int) -> np.ndarray:
    """Fractional input frames of output frames ``start:stop`` (``ratio`` input frames each), snapped to an
    input frame within 1e-6 of one, and past the input's end its last frame."""
    src = np.minimum(np.arange(start, stop) * ratio, n_in - 1)
    near = np.round(src)
    return np.where(np.abs(src - near) < 1e-6, near, src)


def _lerp(values: np.ndarray, src: np.ndarray) -> np.ndarray:
    """[N, ...] float64 ``values`` [T, ...] at fractional frames ``src`` [N] (from :func:`_sources`): input frames
    copied exactly, others interpolated linearly between their two neighbours."""
    lo = np.floor(src).astype(np.int64)
    hi = np.minimum(lo + 1, len(values) - 1)
    w = (src - lo).reshape(-1, *([1] * (values.ndim - 1)))  # [N, 1, ...]
    low = values[lo].astype(np.float64)
    return np.where(w == 0, low, (1 - w) * low + w * values[hi])


def _interpolate(track: PoseTrack, src: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Joints [N, J, 2] and confidence [N, J] at fractional input frames ``src`` [N] (rules of :func:`resample`)."""
    joints, conf = _lerp(track.joints, src), _lerp(track.confidence, src)
    # NaN in either neighbour propagates through the weighted sum, so a half-missing pair stays missing.
    conf = np.where(np.isnan(joints[..., 0]), 0.0, conf)
    return joints.astype(np.float32), conf.astype(np.float32)


__all__ = ["resample", "resample_values", "resampled_frames"]
