"""Everybody Dance Now's global pose normalisation (Chan et al. 2019, §3.3), as small pure functions.

A driver and a reference are filmed from different distances and have different heights. For each video we
find the farthest and the closest position of the feet (the smallest and the largest image y of the lower
ankle) and how tall the performer appears at each. A driver's frame is then scaled and moved so that its
feet land at the linearly corresponding place between the reference's farthest and closest feet, at a scale
interpolated linearly between the height ratios at the two ends:

    a     = (y_foot - s_far) / (s_close - s_far)
    scale = t_h_far / s_h_far + a * (t_h_close / s_h_close - t_h_far / s_h_far)
    foot  = t_far + a * (t_close - t_far)

The paper gives only the vertical mapping. Horizontally we keep the driver's motion: its offset from its own
median foot x is scaled and added to the reference's median foot x. "Min" and "max" are robust quantiles and
"the tallest height" near each end a high quantile, so a few wrong detections do not decide the result.

One guard the paper does not need for its long dance videos: a driver whose feet hardly move vertically
(a range under ``min_span`` of its height, e.g. someone standing in place) has no depth range to map; the
formula would blow its foot jitter up to the reference's whole range. Such a driver keeps one depth: its
median foot position goes to the reference's median foot position, at the mean height ratio.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from pose_io.clean import interpolate_missing
from pose_io.errors import InputError
from pose_io.layouts import JointLayout
from pose_io.measures import apparent_heights, foot_points


@dataclass(frozen=True)
class ScaleStats:
    """Where a performer's feet go in a video and how tall they appear there (image pixels).

    Attributes:
        foot_far: y of the farthest foot position (small y, high in the image).
        foot_close: y of the closest foot position (large y).
        height_far: the performer's apparent height near the farthest position.
        height_close: the performer's apparent height near the closest position.
        center_x: median x of the feet.
        foot_median: median y of the feet (where the performer usually stands).
    """

    foot_far: float
    foot_close: float
    height_far: float
    height_close: float
    center_x: float
    foot_median: float

    @property
    def height(self) -> float:
        """Mean of the far and close heights."""
        return 0.5 * (self.height_far + self.height_close)

    def to_dict(self) -> dict[str, float]:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict) -> ScaleStats:
        keys = ("foot_far", "foot_close", "height_far", "height_close", "center_x", "foot_median")
        return cls(**{k: float(d[k]) for k in keys})


def scale_stats(
    joints: np.ndarray, layout: JointLayout, quantile: float = 0.02, band: float = 0.1, tall: float = 0.9
) -> ScaleStats:
    """The statistics global scaling needs from one video.

    Args:
        joints: [T, J, 2] image pixels, NaN where missing.
        layout: layout of ``joints``.
        quantile: the far and close foot positions are these quantiles of the foot's y.
        band: frames whose foot lies within this fraction of the foot range from an end count as "at" it.
        tall: the height at an end is this quantile of the heights of the frames at it.

    Returns:
        The statistics. Raises InputError when no frame shows an ankle.
    """
    foot = foot_points(joints, layout)  # [T, 2]
    heights = apparent_heights(joints, foot[:, 1])  # [T]
    ok = np.isfinite(foot).all(axis=1) & np.isfinite(heights)
    if not ok.any():
        raise InputError("global scaling needs ankles, and no frame shows one")
    fy, h = foot[ok, 1], heights[ok]
    far, close = np.quantile(fy, quantile), np.quantile(fy, 1.0 - quantile)
    width = band * (close - far)
    h_far = np.quantile(h[fy <= far + width], tall)
    h_close = np.quantile(h[fy >= close - width], tall)
    return ScaleStats(
        foot_far=float(far), foot_close=float(close), height_far=float(max(h_far, 1e-3)),
        height_close=float(max(h_close, 1e-3)), center_x=float(np.median(foot[ok, 0])),
        foot_median=float(np.median(fy)),
    )


def global_scale_params(
    foot_y: np.ndarray, source: ScaleStats, target: ScaleStats, min_span: float = 0.05
) -> tuple[np.ndarray, np.ndarray]:
    """Per-frame scale and target foot y.

    Args:
        foot_y: [T] the source's lower-ankle y per frame (no NaN).
        source: statistics of the source (driver) video.
        target: statistics of the target (reference) video.
        min_span: a source foot range below this fraction of the source's height counts as one depth.

    Returns:
        ``(scale [T], target_foot_y [T])``.
    """
    foot_y = np.asarray(foot_y, dtype=np.float64)
    ratio_far = target.height_far / source.height_far
    ratio_close = target.height_close / source.height_close
    span = source.foot_close - source.foot_far
    if span <= min_span * source.height:
        scale = np.full_like(foot_y, 0.5 * (ratio_far + ratio_close))
        return scale, target.foot_median + scale * (foot_y - source.foot_median)
    a = (foot_y - source.foot_far) / span
    scale = np.maximum(ratio_far + a * (ratio_close - ratio_far), 1e-3)
    target_y = target.foot_far + a * (target.foot_close - target.foot_far)
    return scale, target_y


def apply_global_scale(
    joints: np.ndarray, layout: JointLayout, source: ScaleStats, target: ScaleStats, min_span: float = 0.05
) -> np.ndarray:
    """Move a source track onto a target's feet positions and scale.

    Args:
        joints: [T, J, 2] source image pixels, NaN where missing.
        layout: layout of ``joints``.
        source: statistics of the source (usually ``scale_stats(joints, layout)``).
        target: statistics of the target (reference).
        min_span: see :func:`global_scale_params`.

    Returns:
        [T, J, 2] float32 in the target's image pixels, NaN where the input is NaN. Frames without a visible
        ankle use the foot position interpolated from the neighbouring frames.
    """
    foot = foot_points(joints, layout)  # [T, 2]
    fy = interpolate_missing(foot[:, 1])
    if not np.isfinite(fy).all():
        raise InputError("global scaling needs ankles, and no frame shows one")
    scale, target_y = global_scale_params(fy, source, target, min_span)  # [T], [T]
    out = np.empty(joints.shape, dtype=np.float64)
    out[..., 0] = target.center_x + scale[:, None] * (joints[..., 0] - source.center_x)
    out[..., 1] = target_y[:, None] + scale[:, None] * (joints[..., 1] - fy[:, None])
    return out.astype(np.float32)
