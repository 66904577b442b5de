"""Measures of driven pose tracks, with and without ground-truth poses.

Small numpy functions on ``[T, J, 2]`` pixel arrays (NaN where a joint is missing) and a joint layout; every
joint is found by name. Lengths are in percent of one body height ``height`` (see ``skeleton_height``), so
numbers from different canvases compare. A report measures every method against the *reference's* height, so
the methods share one scale.

* limb-proportion error: each limb of a driven track against the reference's length of that limb (the median
  over the reference's own track), ``|len_t - ref| / height * 100``; a driven skeleton that keeps the reference's
  proportions scores 0.
* foot skating: the horizontal slide of an ankle between two frames in which it is in contact. An ankle is in
  contact when it is within ``height_tol * height`` of its lowest point (largest y) over a centred window and
  moves slowly *vertically* (``|dy| <= speed_tol * height``). Horizontal speed is deliberately not part of the
  contact test, otherwise the test would cap the very slide it measures. The test lives in ``pose_io.contacts``
  (``foot_contacts``), shared with the foot-contact cleanup of `clone drive`.
* temporal jitter: the mean norm of the second difference ``x[t+1] - 2 x[t] + x[t-1]`` of every joint.
* outside share: the share of present joints outside the image.
* against ground-truth poses (``pose_io.compare``, the definitions `clone retarget eval` uses): the pose error
  of the MidHip-aligned poses (each frame's MidHip subtracted from both and left out) as the RMSE of the joint
  distance in % of height (the primary measure), the paper's MSE and PCK of the same; placement, the RMSE of the
  MidHip distance; and the view check, the share of frames facing the same side of the image as the truth.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable

import numpy as np

from clone.metrics.table import Scores, nan_mean, row_means
from pose_io.compare import (
    PCK_ALPHAS,
    aligned_pose_error,
    pck_hits,
    pose_error_terms,
    root_aligned,
    root_distance,
    same_facing,
)
from pose_io.contacts import (  # one home: the cleanup honours the same contacts
    CONTACT_HEIGHT_TOL,
    CONTACT_SPEED_TOL,
    CONTACT_WINDOW,
    contact_window,
    foot_contacts,
)
from pose_io.errors import InputError
from pose_io.layouts import JointLayout
from pose_io.measures import ANKLES, as_layout, check_joints, limb_lengths, skeleton_height
from pose_io.track import PoseTrack

log = logging.getLogger(__name__)


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
    return row_means(errors), errors


def foot_slide(
    joints: np.ndarray,
    height: float,
    layout: JointLayout | str = "body15",
    window: int = CONTACT_WINDOW,
    height_tol: float = CONTACT_HEIGHT_TOL,
    speed_tol: float = CONTACT_SPEED_TOL,
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
    window: int = CONTACT_WINDOW,
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
        summary ``limb_error_pct``, ``foot_slide_pct``, ``foot_slide_px``,
        ``contact_share``, ``jitter_pct``, ``outside_share``; details hold the per-limb error.
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
        "limb_error_pct": nan_mean(limb_all),
        "foot_slide_pct": nan_mean(slide) / height * 100.0,
        "foot_slide_px": nan_mean(slide),
        "contact_share": float(contact.mean()),
        "jitter_pct": nan_mean(acc) / height * 100.0,
        "outside_share": nan_mean(outside),
    }
    per_limb = row_means(limb_all.T)  # [L]
    details = {"limb_error_pct_per_limb": {f"{a}-{b}": float(v) for (a, b), v in zip(layout.limbs, per_limb)}}
    per_frame = {
        "limb_error_pct": limb_frame,
        "foot_slide_pct": row_means(slide) / height * 100.0,
        "jitter_pct": row_means(acc) / height * 100.0,
        "outside_share": row_means(outside),
    }
    return Scores(per_frame, summary, details)


def gt_pose_scores(
    pred: np.ndarray,
    gt: np.ndarray,
    height: float,
    alphas: Iterable[float] = PCK_ALPHAS,
    layout: JointLayout | str = "body15",
) -> Scores:
    """Errors of a driven track against ground-truth poses of the same person and frames.

    Args:
        pred: [T, J, 2] driven track.
        gt: [T, J, 2] ground truth in the same image and layout; joints missing in either are left out.
        height: the target's (ground truth's) height in pixels.
        alphas: PCK thresholds as fractions of ``height``.
        layout: joint layout of both.

    Returns:
        On the MidHip-aligned poses (``pose_io.compare.root_aligned``): ``pose_rmse_pct``, the root of the mean
        squared joint distance in % of height (the primary measure); ``pose_mse``, the mean over frames, joints
        and both coordinates of ``((pred - gt) / height)²`` (height² units); ``pck_<alpha>``, the share of joints
        closer than ``alpha * height``. ``root_rmse_pct``: the RMS distance of the MidHips in % of height
        (placement). ``facing_share``: the share of frames facing the same side as the truth
        (``pose_io.compare.same_facing``). Per-frame curves of the same names.
    """
    layout = as_layout(layout)
    if np.shape(pred) != np.shape(gt):
        raise InputError(f"ground-truth poses: shape {np.shape(gt)} does not match the driven track's {np.shape(pred)}")
    try:
        pred_local, gt_local = root_aligned(pred, layout), root_aligned(gt, layout)  # [T, J - 1, 2] each
        squared, dist = pose_error_terms(pred_local, gt_local, height)  # [T, 2(J - 1)], [T, J - 1] in heights
        total = aligned_pose_error(pred, gt, height, layout, tuple(alphas))
        root = root_distance(pred, gt, height, layout)  # [T] in heights
        facing = same_facing(pred, gt, height, height, layout)  # [T] 1 / 0 / NaN
    except InputError as exc:
        raise InputError(f"ground-truth poses: {exc}") from None
    per_frame = {
        "pose_rmse_pct": np.sqrt(row_means(dist**2)) * 100.0,
        "root_rmse_pct": root * 100.0,
        "facing_share": facing,
        "pose_mse": row_means(squared),
    }
    summary = {
        "pose_rmse_pct": total.pop("rmse_pct"),
        "root_rmse_pct": float(np.sqrt(nan_mean(root**2)) * 100.0),
        "facing_share": nan_mean(facing),
        "pose_mse": total.pop("mse"),
    }
    for alpha in alphas:
        per_frame[f"pck_{alpha:g}"] = row_means(pck_hits(dist, alpha))
    summary.update(total)
    return Scores(per_frame, summary)


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
        scores = scores.merged(track_gt_scores(driven, gt))
    return scores


def track_gt_scores(driven: PoseTrack, gt: PoseTrack) -> Scores:
    """:func:`gt_pose_scores` of a driven track against ground-truth poses of the same frames, normalised by the
    ground truth's own height (the paper's "target's height"); ``gt`` is converted to ``driven``'s layout."""
    if len(gt) != len(driven):
        raise InputError(f"ground-truth poses: {len(gt)} frames, driven track has {len(driven)}")
    if gt.layout != driven.layout:
        gt = gt.to_layout(driven.layout)
    gt_height = skeleton_height(gt.joints, gt.layout)
    return gt_pose_scores(driven.joints, gt.joints, gt_height, layout=driven.layout)
