"""Measures of driven pose tracks and generated frames, for `clone report`.

Pose measures are small numpy functions on ``[T, J, 2]`` pixel arrays (NaN where a joint is missing) and a
joint layout; every joint is found by name. Lengths are given in percent of one body height ``height`` (see
``skeleton_height``), so numbers from different canvases compare. A report measures every method against the
*reference's* height, so the methods share one scale.

The measures:

* limb-proportion error: each limb of a driven track against the reference's length of that limb (the median
  over the reference's own track), ``|len_t - ref| / height * 100``; a driven skeleton that keeps the reference's
  proportions scores 0.
* foot skating: the horizontal slide of an ankle between two frames in which it is in contact. An ankle is in
  contact when it is within ``height_tol * height`` of its lowest point (largest y) over a centred window and
  moves slowly *vertically* (``|dy| <= speed_tol * height``). Horizontal speed is deliberately not part of the
  contact test, otherwise the test would cap the very slide it measures.
* temporal jitter: the mean norm of the second difference ``x[t+1] - 2 x[t] + x[t-1]`` of every joint.
* outside share: the share of present joints outside the image.
* against ground-truth poses: the paper's error, the MSE over frames, joints and both coordinates of
  ``(pred - gt) / height`` (so in height² units; reports show it x 1000); the RMSE of the joint *distance* in %
  of height; PCK, the share of joints within ``alpha * height`` of the truth.
* against ground-truth frames: SSIM and PSNR (scikit-image) on the whole frame and on a crop around the person
  (the box of the ground-truth pose plus a margin). Identical frames have PSNR = inf.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from pose_io.errors import InputError
from pose_io.layouts import JointLayout
from pose_io.measures import (
    ANKLES,
    PCK_ALPHAS,
    as_layout,
    check_joints,
    limb_lengths,
    pck_hits,
    pose_error,
    pose_error_terms,
    skeleton_height,
)
from pose_io.track import PoseTrack

log = logging.getLogger(__name__)



@dataclass(frozen=True)
class MetricInfo:
    """What one summary number means: its label, unit, which direction is better (None: neither, it only
    describes the motion), and its definition."""

    label: str
    unit: str
    better: Literal["lower", "higher"] | None
    meaning: str
    scale: float = 1.0  # multiply by this for display (e.g. MSE in height² shown x 1000)


# Summary keys produced below, in the order a report shows them.
METRICS: dict[str, MetricInfo] = {
    "limb_error_pct": MetricInfo(
        "Limb-length error", "% of height", "lower",
        "mean over frames and limbs of |driven limb length - the reference's median length of that limb|",
    ),
    "foot_slide_pct": MetricInfo(
        "Foot skating", "% of height / frame", "lower",
        "mean horizontal move of an ankle between two frames in which it touches the ground (near its lowest "
        "point within about a second, moving little vertically)",
    ),
    "foot_slide_px": MetricInfo("Foot skating (px)", "px / frame", "lower", "foot skating in pixels of the image"),
    "contact_share": MetricInfo(
        "Ankle contact", "share of ankle-frames", None, "share of ankle-frames judged to touch the ground"
    ),
    "jitter_pct": MetricInfo(
        "Jitter", "% of height / frame²", "lower",
        "mean norm of every joint's second difference x[t+1] - 2 x[t] + x[t-1] (acceleration)",
    ),
    "outside_share": MetricInfo("Joints outside frame", "share", "lower", "share of joints outside the image"),
    "pose_mse": MetricInfo(
        "Pose MSE (paper)", "height² x 10³", "lower",
        "the paper's error: mean over frames, joints and both coordinates of ((driven - true) / height)², "
        "height = the ground truth's; shown x 1000",
        1000.0,
    ),
    "pose_rmse_pct": MetricInfo(
        "Joint RMSE", "% of height", "lower", "root mean squared distance between driven and true joints"
    ),
    "pck_0.05": MetricInfo("PCK@0.05", "share", "higher", "share of joints within 5 % of the height of the truth"),
    "pck_0.1": MetricInfo("PCK@0.1", "share", "higher", "share of joints within 10 % of the height of the truth"),
    "ssim": MetricInfo("SSIM (frame)", "", "higher", "structural similarity of the whole frame to the true frame"),
    "psnr": MetricInfo(
        "PSNR (frame)", "dB", "higher", "peak signal-to-noise ratio of the whole frame (inf when identical)"
    ),
    "ssim_crop": MetricInfo(
        "SSIM (person)", "", "higher", "SSIM of a crop around the true pose's box plus 15 % margin"
    ),
    "psnr_crop": MetricInfo("PSNR (person)", "dB", "higher", "PSNR of the same crop around the person"),
}  # fmt: skip


@dataclass(frozen=True)
class Scores:
    """Per-frame curves and summary numbers of a set of measures of one track or video.

    Attributes:
        per_frame: name -> [T] float64 values, NaN where a frame has no value.
        summary: name -> one number (keys of ``METRICS``).
        details: name -> small JSON-able extras (e.g. the per-limb error).
    """

    per_frame: dict[str, np.ndarray] = field(default_factory=dict)
    summary: dict[str, float] = field(default_factory=dict)
    details: dict[str, object] = field(default_factory=dict)

    def merged(self, other: Scores) -> Scores:
        """Both sets of measures in one (``other`` wins on equal names)."""
        return Scores(
            {**self.per_frame, **other.per_frame},
            {**self.summary, **other.summary},
            {**self.details, **other.details},
        )


def _mean(values: np.ndarray) -> float:
    """Mean of the finite-or-inf values, NaN ignored; NaN when there are none."""
    values = np.asarray(values, dtype=np.float64)
    values = values[~np.isnan(values)]
    return float(values.mean()) if values.size else float("nan")


def _row_means(values: np.ndarray) -> np.ndarray:
    """[T] mean of each row of [T, K] values, NaN ignored; NaN for a row with no value."""
    values = np.asarray(values, dtype=np.float64)
    count = (~np.isnan(values)).sum(axis=1)
    sums = np.nansum(values, axis=1)
    return np.divide(sums, count, out=np.full(count.shape, np.nan), where=count > 0)


def limb_error(
    joints: np.ndarray, reference_lengths: np.ndarray, height: float, layout: JointLayout | str = "body15"
) -> tuple[np.ndarray, np.ndarray]:
    """Limb-length error of a driven track against the reference's limb lengths, in % of ``height``.

    Args:
        joints: [T, J, 2] driven track.
        reference_lengths: [L] reference limb lengths (``reference_limb_lengths``).
        height: the reference's height in pixels.
        layout: joint layout of ``joints``.

    Returns:
        per_frame: [T] mean over limbs of ``|len - ref| / height * 100``, NaN where no limb is seen.
        errors: [T, L] the per-limb errors, NaN where a limb is not seen.
    """
    layout = as_layout(layout)
    lengths = limb_lengths(joints, layout)
    reference_lengths = np.asarray(reference_lengths, dtype=np.float64)
    if reference_lengths.shape != (lengths.shape[1],):
        raise InputError(
            f"limb error: {lengths.shape[1]} limbs, but {reference_lengths.shape} reference lengths"
        )
    errors = np.abs(lengths - reference_lengths) / height * 100.0
    return _row_means(errors), errors


def _window_max(values: np.ndarray, window: int) -> np.ndarray:
    """[T] NaN-ignoring maximum of ``values`` [T] over a centred window of ``window`` frames."""
    half = max(0, window // 2)
    padded = np.pad(values, half, constant_values=np.nan)
    windows = np.lib.stride_tricks.sliding_window_view(padded, 2 * half + 1)  # [T, 2 half + 1]
    out = np.full(values.shape, np.nan)
    seen = ~np.isnan(windows).all(axis=1)
    out[seen] = np.nanmax(windows[seen], axis=1)
    return out


def foot_contacts(
    joints: np.ndarray,
    height: float,
    layout: JointLayout | str = "body15",
    window: int = 31,
    height_tol: float = 0.02,
    speed_tol: float = 0.01,
) -> np.ndarray:
    """Which ankles touch the ground in which frames.

    Args:
        joints: [T, J, 2] pixel coordinates (y down).
        height: body height in pixels; the tolerances are fractions of it.
        layout: joint layout of ``joints`` (needs ``l_ankle``, ``r_ankle``).
        window: frames of the centred window whose lowest ankle point is the ground (about a second).
        height_tol: how far above that point (in heights) an ankle may be and still touch.
        speed_tol: the largest vertical move (heights per frame) of an ankle that touches.

    Returns:
        [T, 2] bool, columns in ``ANKLES`` order.
    """
    layout = as_layout(layout)
    feet = check_joints(joints, layout, "foot contacts")[:, layout.indices(ANKLES)]  # [T, 2, 2]
    y = feet[..., 1]  # [T, 2]
    contact = np.zeros(y.shape, dtype=bool)
    for f in range(y.shape[1]):
        ground = _window_max(y[:, f], window)
        dy = np.abs(np.diff(y[:, f]))
        speed = np.concatenate([dy[:1], dy]) if dy.size else np.zeros(1)  # frame 0 uses the next step
        with np.errstate(invalid="ignore"):
            contact[:, f] = (y[:, f] >= ground - height_tol * height) & (speed <= speed_tol * height)
    return contact


def foot_slide(
    joints: np.ndarray,
    height: float,
    layout: JointLayout | str = "body15",
    window: int = 31,
    height_tol: float = 0.02,
    speed_tol: float = 0.01,
) -> tuple[np.ndarray, np.ndarray]:
    """Horizontal ankle slide while in contact (see ``foot_contacts`` for the arguments).

    Returns:
        slide: [T, 2] pixels moved in x from frame t-1 to t by each ankle that touches in both frames, NaN
            otherwise (always NaN in frame 0).
        contact: [T, 2] bool contact flags.
    """
    layout = as_layout(layout)
    contact = foot_contacts(joints, height, layout, window, height_tol, speed_tol)
    x = np.asarray(joints, dtype=np.float64)[:, layout.indices(ANKLES), 0]  # [T, 2]
    slide = np.full(x.shape, np.nan)
    both = contact[1:] & contact[:-1]
    slide[1:][both] = np.abs(np.diff(x, axis=0))[both]
    return slide, contact


def jitter(joints: np.ndarray) -> np.ndarray:
    """Acceleration of every joint: the norm of its second difference.

    Args:
        joints: [T, J, 2] pixel coordinates, NaN where missing.

    Returns:
        [T, J] pixels per frame², the value at t centred on t; NaN in the first and last frame and next to
        missing joints.
    """
    joints = np.asarray(joints, dtype=np.float64)
    out = np.full(joints.shape[:2], np.nan)
    if joints.shape[0] >= 3:
        out[1:-1] = np.linalg.norm(joints[2:] - 2.0 * joints[1:-1] + joints[:-2], axis=-1)
    return out


def outside_frame(joints: np.ndarray, image_size: tuple[int, int]) -> np.ndarray:
    """Which joints lie outside the image.

    Args:
        joints: [T, J, 2] pixel coordinates, NaN where missing.
        image_size: (width, height) of the image.

    Returns:
        [T, J] 1.0 outside, 0.0 inside, NaN where missing (row means are shares of the present joints).
    """
    joints = np.asarray(joints, dtype=np.float64)
    w, h = image_size
    x, y = joints[..., 0], joints[..., 1]
    with np.errstate(invalid="ignore"):
        outside = ((x < 0) | (x > w) | (y < 0) | (y > h)).astype(np.float64)
    outside[np.isnan(x) | np.isnan(y)] = np.nan
    return outside


def pose_scores(
    joints: np.ndarray,
    image_size: tuple[int, int],
    reference_lengths: np.ndarray,
    height: float,
    layout: JointLayout | str = "body15",
    window: int = 31,
) -> Scores:
    """All ground-truth-free measures of one driven track.

    Args:
        joints: [T, J, 2] driven track in the reference's image.
        image_size: (width, height) of that image.
        reference_lengths: [L] the reference's limb lengths.
        height: the reference's height in pixels.
        layout: joint layout of ``joints``.
        window: contact window in frames (about one second).

    Returns:
        Per-frame curves ``limb_error_pct``, ``foot_slide_pct``, ``jitter_pct``, ``outside_share`` and the
        summary of ``METRICS``'s first six keys; details hold the per-limb error.
    """
    layout = as_layout(layout)
    if not height > 0:
        raise InputError(f"pose scores: height must be positive, got {height}")
    joints = check_joints(joints, layout, "pose scores")
    limb_frame, limb_all = limb_error(joints, reference_lengths, height, layout)
    slide, contact = foot_slide(joints, height, layout, window)
    acc = jitter(joints)
    outside = outside_frame(joints, image_size)
    summary = {
        "limb_error_pct": _mean(limb_all),
        "foot_slide_pct": _mean(slide) / height * 100.0,
        "foot_slide_px": _mean(slide),
        "contact_share": float(contact.mean()),
        "jitter_pct": _mean(acc) / height * 100.0,
        "outside_share": _mean(outside),
    }
    per_limb = _row_means(limb_all.T)  # [L]
    details = {"limb_error_pct_per_limb": {f"{a}-{b}": float(v) for (a, b), v in zip(layout.limbs, per_limb)}}
    per_frame = {
        "limb_error_pct": limb_frame,
        "foot_slide_pct": _row_means(slide) / height * 100.0,
        "jitter_pct": _row_means(acc) / height * 100.0,
        "outside_share": _row_means(outside),
    }
    return Scores(per_frame, summary, details)


def gt_pose_scores(
    pred: np.ndarray, gt: np.ndarray, height: float, alphas: Iterable[float] = PCK_ALPHAS
) -> Scores:
    """Errors of a driven track against ground-truth poses of the same person and frames.

    Args:
        pred: [T, J, 2] driven track.
        gt: [T, J, 2] ground truth in the same image and layout; joints missing in either are left out.
        height: the target's (ground truth's) height in pixels.
        alphas: PCK thresholds as fractions of ``height``.

    Returns:
        ``pose_mse``: mean over frames, joints and both coordinates of ``((pred - gt) / height)²`` (height²
        units); ``pose_rmse_pct``: root of the mean squared joint distance, in % of height; ``pck_<alpha>``:
        share of joints closer than ``alpha * height``. Per-frame curves of the same names.
    """
    try:
        squared, dist = pose_error_terms(pred, gt, height)  # [T, 2J], [T, J] in heights
    except InputError as exc:
        raise InputError(f"ground-truth poses: {str(exc).removeprefix('pose error: ')}") from None
    total = pose_error(pred, gt, height, tuple(alphas))
    per_frame = {"pose_mse": _row_means(squared), "pose_rmse_pct": np.sqrt(_row_means(dist**2)) * 100.0}
    summary = {"pose_mse": total.pop("mse"), "pose_rmse_pct": total.pop("rmse_pct")}
    for alpha in alphas:
        per_frame[f"pck_{alpha:g}"] = _row_means(pck_hits(dist, alpha))
    summary.update(total)
    return Scores(per_frame, summary)


def person_box(
    joints: np.ndarray, image_size: tuple[int, int], margin: float = 0.15, min_size: int = 7
) -> tuple[int, int, int, int] | None:
    """Box around one pose, for a crop.

    Args:
        joints: [J, 2] pixel coordinates, NaN where missing.
        image_size: (width, height) of the image.
        margin: added on every side, as a fraction of the larger side of the joints' box (joints stop at the
            ankles and nose, the person does not).
        min_size: smallest side of the box (SSIM needs 7 pixels), if the image allows.

    Returns:
        (x0, y0, x1, y1) integer pixel box inside the image (x1, y1 exclusive), or None if no joint is present.
    """
    joints = np.asarray(joints, dtype=np.float64)
    ok = ~np.isnan(joints).any(axis=-1)
    if not ok.any():
        return None
    w, h = image_size
    lo, hi = joints[ok].min(axis=0), joints[ok].max(axis=0)
    pad = margin * float((hi - lo).max())
    box = []
    for axis, limit in ((0, w), (1, h)):
        a, b = lo[axis] - pad, hi[axis] + pad
        grow = max(0.0, min(min_size, limit) - (b - a)) / 2
        a, b = int(np.floor(max(0.0, a - grow))), int(np.ceil(min(float(limit), b + grow)))
        if b - a < min(min_size, limit):  # pushed against an edge: extend the other way
            a, b = (0, min(min_size, limit)) if a == 0 else (limit - min(min_size, limit), limit)
        box.append((a, b))
    (x0, x1), (y0, y1) = box
    return x0, y0, x1, y1


def frame_pair_scores(pred: np.ndarray, gt: np.ndarray) -> tuple[float, float]:
    """SSIM and PSNR (dB) of one generated frame against the true one.

    Args:
        pred: [H, W, 3] uint8 RGB generated frame.
        gt: [H, W, 3] uint8 RGB ground truth of the same size (at least 7 x 7).

    Returns:
        (ssim, psnr); psnr is inf for identical frames.
    """
    from skimage.metrics import peak_signal_noise_ratio, structural_similarity

    if pred.shape != gt.shape:
        raise InputError(f"ground-truth frame: size {gt.shape} does not match the generated {pred.shape}")
    ssim = structural_similarity(pred, gt, channel_axis=-1, data_range=255)
    with np.errstate(divide="ignore"):  # identical frames: MSE 0, PSNR inf
        psnr = peak_signal_noise_ratio(gt, pred, data_range=255)
    return float(ssim), float(psnr)


class FrameScorer:
    """Collects SSIM/PSNR of generated frames against the truth, one frame at a time.

    Frames arrive one by one from a generator, so a whole video never has to sit in memory.
    """

    def __init__(self, gt_joints: np.ndarray | None = None, margin: float = 0.15) -> None:
        """Args:
        gt_joints: [T, J, 2] ground-truth poses for the person crop, or None for whole frames only.
        margin: crop margin (see ``person_box``).
        """
        self.gt_joints = gt_joints
        self.margin = margin
        self._rows: list[tuple[float, float, float, float]] = []

    def add(self, pred: np.ndarray, gt: np.ndarray) -> None:
        """Score the next frame pair ([H, W, 3] uint8 RGB each)."""
        t = len(self._rows)
        if self.gt_joints is not None and t >= len(self.gt_joints):
            raise InputError(
                f"ground-truth poses: only {len(self.gt_joints)} frames, more video frames given"
            )
        ssim, psnr = frame_pair_scores(pred, gt)
        crop = (float("nan"), float("nan"))
        if self.gt_joints is not None:
            box = person_box(self.gt_joints[t], (gt.shape[1], gt.shape[0]), self.margin)
            if box is not None:
                x0, y0, x1, y1 = box
                crop = frame_pair_scores(pred[y0:y1, x0:x1], gt[y0:y1, x0:x1])
        self._rows.append((ssim, psnr, *crop))

    def scores(self) -> Scores:
        """``ssim``, ``psnr`` (and ``ssim_crop``, ``psnr_crop`` with ground-truth poses): per frame and mean."""
        names = ("ssim", "psnr", "ssim_crop", "psnr_crop")[: 4 if self.gt_joints is not None else 2]
        table = np.array(self._rows, dtype=np.float64).reshape(-1, 4)
        per_frame = {n: table[:, i] for i, n in enumerate(names)}
        return Scores(per_frame, {n: _mean(v) for n, v in per_frame.items()})


def frame_scores(
    pred_frames: Sequence[np.ndarray], gt_frames: Sequence[np.ndarray], gt_joints: np.ndarray | None = None
) -> Scores:
    """SSIM/PSNR of a generated video against the true one (see ``FrameScorer``).

    Args:
        pred_frames: T frames [H, W, 3] uint8 RGB (or a [T, H, W, 3] array).
        gt_frames: T frames of the same size.
        gt_joints: [T, J, 2] ground-truth poses for the person crop, or None.
    """
    scorer = FrameScorer(gt_joints)
    if len(pred_frames) != len(gt_frames):
        raise InputError(
            f"ground-truth frames: {len(gt_frames)} frames, generated video has {len(pred_frames)}"
        )
    if gt_joints is not None and len(gt_joints) != len(pred_frames):
        raise InputError(f"ground-truth poses: {len(gt_joints)} frames, video has {len(pred_frames)}")
    for pred, gt in zip(pred_frames, gt_frames):
        scorer.add(pred, gt)
    return scorer.scores()


def contact_window(fps: float) -> int:
    """Odd number of frames closest to one second: the window in which an ankle's lowest point is the ground."""
    return round(fps) // 2 * 2 + 1


def evaluate_track(
    driven: PoseTrack,
    reference_lengths: np.ndarray,
    height: float,
    gt: PoseTrack | None = None,
) -> Scores:
    """Pose measures of a driven track, and its errors against ground-truth poses when given.

    Args:
        driven: the driven track in the reference's image.
        reference_lengths: [L] the reference's limb lengths in ``driven``'s layout.
        height: the reference's height in pixels (scale of the ground-truth-free measures).
        gt: ground-truth poses of the same frames; their errors are normalised by the ground truth's own
            height (the paper's "target's height"), and its layout is converted to ``driven``'s.
    """
    scores = pose_scores(
        driven.joints, driven.image_size, reference_lengths, height, driven.layout, contact_window(driven.fps)
    )
    if gt is not None:
        if len(gt) != len(driven):
            raise InputError(f"ground-truth poses: {len(gt)} frames, driven track has {len(driven)}")
        if gt.layout != driven.layout:
            gt = gt.to_layout(driven.layout)
        gt_height = skeleton_height(gt.joints, gt.layout)
        scores = scores.merged(gt_pose_scores(driven.joints, gt.joints, gt_height))
    return scores
