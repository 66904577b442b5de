"""Real tracks as the network takes them: body15 without outlier joints, gaps filled, resampled to the
network's rate, smoothed and scaled to the network canvas (:func:`prepare`); and the reverse direction's
helper, synthesised body15 tracks (:func:`body15_track`). The tensor itself: :mod:`retarget.network.preprocess`."""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from pose_io.clean import drop_outlier_joints, hold_fill, smooth_joints
from pose_io.errors import InputError
from pose_io.layouts import convert_joints, get_layout, require_convertible
from pose_io.measures import skeleton_height
from pose_io.resample import resample_values
from pose_io.track import PoseTrack
from retarget.network.preprocess import LAYOUT, PreprocessConfig

log = logging.getLogger(__name__)

# A body shorter than this (pixels) cannot be measured, and scaling it to a canvas would blow noise up.
_MIN_BODY_HEIGHT = 1.0

def to_body15(track: PoseTrack, name: str = "track") -> PoseTrack:
    """``track`` in body15 with outlier joints dropped; InputError when its layout cannot give all body15 joints.

    Every real track enters the network through here, so a joint far outside the image and far from its
    body (rules in :mod:`pose_io.limits`) never scales or places the body: it is made missing before the
    layout conversion, with one warning naming ``name``. Tracks read by :mod:`pose_io.readers` have
    been through the same rule already.
    """
    return _without_outliers(track, name).to_layout(LAYOUT.name)


def _without_outliers(track: PoseTrack, name: str) -> PoseTrack:
    """``track`` (any layout that can give body15) with outlier joints dropped, warning once."""
    try:
        require_convertible(get_layout(track.layout), LAYOUT)
    except InputError as exc:
        raise InputError(f"{name}: {exc}") from None
    track, dropped = drop_outlier_joints(track)
    if dropped.count:
        log.warning("%s", dropped.message(name))
    return track


def _body15_joints(track: PoseTrack, name: str) -> np.ndarray:
    """``to_body15(track, name).joints`` ([T, 15, 2] float32) without validating a new body15 track; a body15
    track's own joints (read-only), not a copy of them."""
    track = _without_outliers(track, name)
    if track.layout == LAYOUT.name:
        return track.joints
    return convert_joints(track.joints, track.joint_layout, LAYOUT)


def canvas_scale(image_size: tuple[int, int], config: PreprocessConfig, joints: np.ndarray | None = None) -> float:
    """Factor from a track's pixels to the network canvas.

    Args:
        image_size: (width, height) of the track's frames.
        config: preprocessing settings.
        joints: [T, 15, 2] body15 pixels (NaN allowed); needed when ``config.body_height`` > 0.
    """
    if config.body_height > 0:
        if joints is None:
            raise ValueError("body-height normalisation needs the joints")
        height = skeleton_height(joints, LAYOUT)
        if height < _MIN_BODY_HEIGHT:
            raise InputError(f"skeleton height: {height:.3g} pixels; a body must be at least {_MIN_BODY_HEIGHT:g} "
                             "pixel tall to be scaled")
        return config.body_height / height
    return config.canvas_height / float(image_size[1])


def filled_body15(track: PoseTrack, name: str = "track") -> np.ndarray:
    """A track in body15 with every gap filled (:func:`hold_fill`), in its own pixels.

    Args:
        track: any layout that can give body15.
        name: how error messages call the track.

    Returns:
        [T, 15, 2] float64.

    Raises:
        InputError: layout not convertible, no joint detected at all, or a joint never detected.
    """
    return _filled(to_body15(track, name).joints, name)


def _filled(joints: np.ndarray, name: str) -> np.ndarray:
    """[T, 15, 2] body15 pixels with NaN gaps -> filled float64 (see :func:`filled_body15`; a float64 input
    without gaps comes back as it is)."""
    joints = np.asarray(joints, dtype=np.float64)
    seen = ~np.isnan(joints[..., 0])
    if seen.all():
        return joints  # nothing to fill: what hold_fill would give
    if not seen.any():
        raise InputError(f"{name}: no joints detected in any of its {len(joints)} frames")
    never = [LAYOUT.joints[j] for j in np.flatnonzero(~seen.any(axis=0))]
    if never:
        raise InputError(f"{name}: joints never detected in any frame: {', '.join(never)}")
    return hold_fill(joints)


@dataclass(frozen=True, eq=False)
class PreparedTrack:
    """A real track as the network takes it, and what placing its result needs.

    Attributes:
        canvas: [T', 15, 2] float64 clean body15 poses in the network canvas (at the rate asked for).
        scale: the factor from the track's pixels to the canvas.
        body15: [T, 15, 2] body15 joints in the track's own pixels (outliers dropped, gaps NaN).
    """

    canvas: np.ndarray
    scale: float
    body15: np.ndarray


def prepare(
    track: PoseTrack, config: PreprocessConfig, name: str = "track", fps: float | None = None
) -> PreparedTrack:
    """A real track as clean body15 poses in the network canvas (the authors' preprocessing).

    Converts to body15 once (dropping outlier joints), fills gaps (:func:`hold_fill`), resamples to ``fps``
    if given (:func:`pose_io.resample.resample_values`: after the filling, so a flickering joint does not turn
    into wider gaps), smooths over time and scales to the canvas (:func:`canvas_scale`: by the skeleton
    height, or by the image height for the authors' weights).

    Raises:
        InputError: see :func:`filled_body15`, or a body too small to scale.
    """
    body = _body15_joints(track, name)
    body64 = body.astype(np.float64)  # converted once, for the filling and the skeleton height
    filled = _filled(body64, name)
    if fps is not None and fps != track.fps:
        filled = resample_values(filled, track.fps, fps)  # [T', 15, 2], a new array
    scale = _scale(track.image_size, config, body64, name)
    canvas = smooth_joints(filled, config.input_sigma, out=filled)  # filled is ours (body64 or a new array)
    canvas *= scale
    return PreparedTrack(canvas, scale, body)


def prepare_track(track: PoseTrack, config: PreprocessConfig, name: str = "track") -> np.ndarray:
    """[T, 15, 2] float64 canvas poses of a real track (:func:`prepare`)."""
    return prepare(track, config, name).canvas


def track_scale(track: PoseTrack, config: PreprocessConfig, name: str = "track") -> float:
    """Factor :func:`prepare` scales ``track`` by (its pixels -> the network canvas)."""
    if config.body_height <= 0:
        return canvas_scale(track.image_size, config)
    return _scale(track.image_size, config, to_body15(track, name).joints, name)


def _scale(image_size: tuple[int, int], config: PreprocessConfig, body15: np.ndarray, name: str) -> float:
    try:
        return canvas_scale(image_size, config, body15)
    except InputError as exc:
        raise InputError(f"{name}: {exc}") from None


def body15_track(joints: np.ndarray, fps: float, image_size: tuple[int, int]) -> PoseTrack:
    """A synthesised body15 track: [T, 15, 2] pixels, every joint present (confidence 1)."""
    return PoseTrack.complete(joints, fps, image_size, LAYOUT.name)
