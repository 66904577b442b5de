"""Where a driven track goes in the reference's picture: inside the frame with its travel kept (``frame``, the
default), or on the reference's stage, the part of the floor the reference stood on in its video (``reference``).

A retargeted track first starts where the reference stands (:func:`start_on_reference`): the median root x and
foot line of its first half second are moved onto the reference's medians, and from there it travels as the
driver does. (The network places a whole window by its median, which puts the start of a walk half its travel
away from the reference.) Then the one affine map per axis below keeps it in bounds: for ``frame`` the bounds are
the model's picture, less the body's own extent and a margin, so a driver's walk across the room is kept as long
as it stays in the picture and is only compressed when it is longer than the picture is wide; for ``reference``
they are the reference's own ranges, and a track moved in depth there also takes the size the reference had at
its new foot line.

``reference`` is for a generator that should only paint where it saw the reference: a driven trajectory that
walks off that part of the frame (or towards the camera) asks it for something it never learnt, but squeezing
a walk into a small range makes the feet slide and misplaces the body (docs/cloning.md measures both). The
reference's stage is the robust range (2nd to 98th percentile) of its root's (``mid_hip``) horizontal positions
and of its foot line (the lower ankle's image y), and how its apparent height changes along that line: linearly
in the foot's y between the farthest and the closest position, as in Everybody Dance Now's normalisation
(:mod:`retarget.baselines.global_scale`).

A track already in bounds is returned unchanged. Otherwise each axis gets ONE affine map of its whole
trajectory (a shift when the track's range fits, else a shift and a compression), so the motion keeps its shape
and velocities stay continuous; no frame is clamped on its own, which would make the feet slide:

    foot'  = foot_scale * foot + foot_shift        (the foot line, image y)
    k(t)   = h(foot'(t)) / h(foot(t))              (the EDN height line h; 1 for ``frame``)
    pose'  = anchor' + k(t) * (pose - anchor)      (about the root's x and the foot line)
    x''    = x' + (x_scale - 1) * root_x + x_shift (the root's x range; the body moves rigidly with it)
"""

from __future__ import annotations

import logging
import warnings
from dataclasses import dataclass, replace

import numpy as np

from pose_io.clean import interpolate_missing
from pose_io.errors import InputError
from pose_io.measures import ANKLES, foot_points
from pose_io.track import PoseTrack

log = logging.getLogger(__name__)

ROOT = "mid_hip"


@dataclass(frozen=True)
class StageConfig:
    """How the reference's stage is measured and how much slack a driven track gets.

    Attributes:
        percentile: the reference's ranges of root x and foot y run from this percentile to 100 minus it.
        margin: slack around those ranges, as a fraction of the reference's apparent height.
        min_span: a reference foot range under this fraction of its height is one depth (constant size).
        max_slope: the most apparent height gained per pixel the feet come down: a pinhole camera gives the
            performer's height over the camera's height, 2 for a camera at half the performer's height.
        min_frames: fewer reference frames showing a root and an ankle give no stage (the track is kept).
        start_seconds: a retargeted track's start, whose median is put where the reference stands.
    """

    percentile: float = 2.0
    margin: float = 0.05
    min_span: float = 0.05
    max_slope: float = 2.0
    min_frames: int = 8
    start_seconds: float = 0.5


@dataclass(frozen=True)
class StageFit:
    """What :func:`fit_to_stage` did.

    Attributes:
        share: share of frames (0..1) whose root x or foot y lay outside the bounds (ranges + margin) before.
        x_scale: root x' = x_scale * x + x_shift (1, 0: unchanged).
        x_shift: see ``x_scale`` (pixels).
        foot_scale: foot y' = foot_scale * y + foot_shift (1, 0: unchanged).
        foot_shift: see ``foot_scale`` (pixels).
        x_range: the root x range kept to (pixels): the reference's robust one, or where the picture holds the
            body; NaN when the reference gives no stage.
        foot_range: the foot y range kept to, farthest to closest (pixels); NaN likewise.
        margin: slack around both ranges (pixels).
        reason: why the track was left as it is without being measured ("" when it was measured).
    """

    share: float
    x_scale: float = 1.0
    x_shift: float = 0.0
    foot_scale: float = 1.0
    foot_shift: float = 0.0
    x_range: tuple[float, float] = (float("nan"), float("nan"))
    foot_range: tuple[float, float] = (float("nan"), float("nan"))
    margin: float = 0.0
    reason: str = ""

    @property
    def moved(self) -> bool:
        """Whether the track was changed."""
        return (self.x_scale, self.x_shift, self.foot_scale, self.foot_shift) != (1.0, 0.0, 1.0, 0.0)


@dataclass(frozen=True)
class Stage:
    """The reference's stage in its pixels: ranges, margin, and the EDN height line ``h0 + slope * foot_y``."""

    x_range: tuple[float, float]
    foot_range: tuple[float, float]
    margin: float
    h0: float
    slope: float
    floor: float  # the smallest height the line may give (it is extrapolated outside the foot range)

    def height(self, foot_y: np.ndarray) -> np.ndarray:
        return np.maximum(self.h0 + self.slope * foot_y, self.floor)


def _root_and_foot(track: PoseTrack) -> tuple[np.ndarray, np.ndarray]:
    """[T] root x and [T] lower-ankle y, NaN where missing; InputError when the layout lacks them."""
    layout = track.joint_layout
    if ROOT not in layout.joints or not all(a in layout.joints for a in ANKLES):
        raise InputError(f"layout {layout.name} has no {ROOT} or no ankles")
    return track.joint(ROOT)[:, 0].astype(np.float64), foot_points(track.joints, layout)[:, 1]


def reference_stage(reference: PoseTrack, config: StageConfig = StageConfig()) -> Stage:
    """The stage of ``reference``; InputError (its message is the reason) when it shows none."""
    from retarget.baselines.global_scale import scale_stats  # the EDN measures: one home

    root_x, foot_y = _root_and_foot(reference)
    ok = np.isfinite(root_x) & np.isfinite(foot_y)
    if ok.sum() < config.min_frames:
        raise InputError(f"the reference shows its root and an ankle in {int(ok.sum())} frames "
                         f"(at least {config.min_frames} needed)")
    stats = scale_stats(reference.joints[ok], reference.joint_layout, quantile=config.percentile / 100.0)
    height = stats.height
    x_lo, x_hi = np.percentile(root_x[ok], [config.percentile, 100.0 - config.percentile])
    far, close = stats.foot_far, stats.foot_close
    slope = 0.0
    if close - far > config.min_span * height:
        # Apparent heights also follow the pose (arms up, crouching): a performer who appears smaller when
        # closer is the pose speaking, not the camera, so the line never falls and never rises absurdly fast.
        slope = float(np.clip((stats.height_close - stats.height_far) / (close - far), 0.0, config.max_slope))
    h0 = height - slope * 0.5 * (far + close)  # the line through the mean height at the middle of the range
    return Stage((float(x_lo), float(x_hi)), (float(far), float(close)), config.margin * height, h0, slope,
                  0.1 * min(stats.height_far, stats.height_close))


def fit_interval(lo: float, hi: float, low: float, high: float) -> tuple[float, float]:
    """``(scale, shift)`` of the smallest affine map that brings ``[lo, hi]`` inside ``[low, high]``.

    (1, 0) when it is inside; a pure shift to the nearer edge when it fits; else a compression onto the range.
    """
    lo, hi, low, high = float(lo), float(hi), float(low), float(high)
    if lo >= low and hi <= high:
        return 1.0, 0.0
    if hi - lo <= high - low:
        return 1.0, (low - lo) if lo < low else (high - hi)
    scale = (high - low) / (hi - lo)
    return scale, low - scale * lo


def picture_stage(track: PoseTrack, root_x: np.ndarray, foot_y: np.ndarray, stage: Stage,
                  picture: tuple[float, float, float, float]) -> Stage:
    """The stage of a whole picture ``(x0, y0, x1, y1)``: where ``track``'s root x and foot line may go so that
    every joint stays ``stage.margin`` inside it; the reference's height line is kept."""
    joints = track.joints.astype(np.float64)  # [T, J, 2]
    with warnings.catch_warnings():  # a frame without anybody in it has no extent (NaN), and is ignored
        warnings.simplefilter("ignore", category=RuntimeWarning)
        left = float(np.nanmax(root_x - np.nanmin(joints[..., 0], axis=1)))
        right = float(np.nanmax(np.nanmax(joints[..., 0], axis=1) - root_x))
        up = float(np.nanmax(foot_y - np.nanmin(joints[..., 1], axis=1)))
    x0, y0, x1, y1 = picture
    m = stage.margin
    x_range = (x0 + m + max(left, 0.0), x1 - m - max(right, 0.0))
    foot_range = (y0 + m + max(up, 0.0), y1 - m)
    # a body wider or taller than the picture: its root's range collapses to the middle
    x_range = x_range if x_range[0] <= x_range[1] else (0.5 * sum(x_range),) * 2
    foot_range = foot_range if foot_range[0] <= foot_range[1] else (0.5 * sum(foot_range),) * 2
    return replace(stage, x_range=x_range, foot_range=foot_range, margin=0.0)


def start_on_reference(track: PoseTrack, reference: PoseTrack, config: StageConfig = StageConfig()) -> PoseTrack:
    """``track`` moved so that its first ``config.start_seconds`` stand where ``reference`` stands (medians of
    root x and foot line); unchanged when either never shows a root and an ankle there."""
    root_x, foot_y = _root_and_foot(track)
    ref_x, ref_foot = _root_and_foot(reference)
    seen = np.flatnonzero(np.isfinite(root_x) & np.isfinite(foot_y))
    ref_seen = np.isfinite(ref_x) & np.isfinite(ref_foot)
    if not len(seen) or not ref_seen.any():
        return track
    start = seen[: max(1, round(config.start_seconds * track.fps))]
    shift = np.array([np.median(ref_x[ref_seen]) - np.median(root_x[start]),
                      np.median(ref_foot[ref_seen]) - np.median(foot_y[start])])
    return track.replace(joints=(track.joints + shift).astype(np.float32))


def fit_to_stage(
    track: PoseTrack, reference: PoseTrack, config: StageConfig = StageConfig(),
    picture: tuple[float, float, float, float] | None = None,
) -> tuple[PoseTrack, StageFit]:
    """Move ``track`` into bounds: the whole ``picture``, or the part of the frame ``reference`` occupied (see the
    module docstring).

    Args:
        track: the driven poses, [T, J, 2] in the reference's image pixels, NaN where missing.
        reference: the reference's own track in the same pixels.
        config: percentiles and margins.
        picture: ``(x0, y0, x1, y1)`` in those pixels: keep every joint inside it (a margin from its edges) and
            the travel as it is where it fits; None: keep the root and feet on the reference's stage.

    Returns:
        ``(track, fit)``: the moved track (the same object when nothing moved; missing joints stay NaN) and
        what was done. A reference without a stage (no root or ankles, too few frames) or a track without a
        root or feet leaves the track as it is, with the reason logged and kept in ``fit.reason``.
    """
    try:
        stage = reference_stage(reference, config)
        root_x, foot_y = (interpolate_missing(v) for v in _root_and_foot(track))  # [T], [T]
        if not (np.isfinite(root_x).all() and np.isfinite(foot_y).all()):
            raise InputError(f"the driven track never shows its {ROOT} or an ankle")
    except InputError as exc:
        log.warning("driven track kept where it is (no stage to fit it to): %s", exc)
        return track, StageFit(share=0.0, reason=str(exc))
    if picture is not None:
        stage = picture_stage(track, root_x, foot_y, stage, picture)

    m = stage.margin
    (x_lo, x_hi), (far, close) = stage.x_range, stage.foot_range
    outside = (root_x < x_lo - m) | (root_x > x_hi + m) | (foot_y < far - m) | (foot_y > close + m)  # [T]
    foot_scale, foot_shift = fit_interval(foot_y.min(), foot_y.max(), far - m, close + m)
    x_scale, x_shift = fit_interval(root_x.min(), root_x.max(), x_lo - m, x_hi + m)
    fit = StageFit(float(outside.mean()), x_scale, x_shift, foot_scale, foot_shift, stage.x_range,
                   stage.foot_range, m)
    if not fit.moved:
        return track, fit

    joints = track.joints.astype(np.float64)  # [T, J, 2]
    new_foot = foot_scale * foot_y + foot_shift  # [T]
    # [T] EDN change of apparent size with depth, on the reference's stage; in the picture the map only keeps
    # the body in view (a jump near the top edge is no step away from the camera), so sizes stay as they are
    k = np.ones_like(foot_y) if picture is not None else stage.height(new_foot) / stage.height(foot_y)
    out = np.empty_like(joints)
    out[..., 0] = root_x[:, None] + k[:, None] * (joints[..., 0] - root_x[:, None])
    out[..., 1] = new_foot[:, None] + k[:, None] * (joints[..., 1] - foot_y[:, None])
    out[..., 0] += ((x_scale - 1.0) * root_x + x_shift)[:, None]  # the body moves rigidly with its root
    log.info("kept %s: %.0f%% of %d frames were off it (root x %.3g*x%+.1f px, foot y "
             "%.3g*y%+.1f px, size x%.3g..%.3g)", "in the picture" if picture else "on the reference's stage",
             100 * fit.share, track.num_frames, x_scale, x_shift,
             foot_scale, foot_shift, k.min(), k.max())
    return track.replace(joints=out.astype(np.float32)), fit
