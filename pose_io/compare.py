"""Measures comparing a pose track with another (a prediction with the truth): the pose error and its
companions, the same without placement (root-aligned), the placement error and the facing check.

Small pure numpy functions on ``[T, J, 2]`` pixel arrays (NaN where a joint is missing); one definition of each,
used by ``clone retarget eval`` and ``clone report``.
"""

from __future__ import annotations

import numpy as np

from pose_io.errors import InputError
from pose_io.layouts import JointLayout
from pose_io.measures import as_layout, check_joints

PCK_ALPHAS: tuple[float, ...] = (0.05, 0.1)


def pose_error_terms(pred: np.ndarray, truth: np.ndarray, height: float) -> tuple[np.ndarray, np.ndarray]:
    """Height-normalised differences of two pose tracks: the terms every pose error is built from.

    Args:
        pred: [T, J, 2] pixels, NaN where missing.
        truth: [T, J, 2] pixels, NaN where missing.
        height: the target's body height in pixels.

    Returns:
        ``(squared, distance)``: [T, 2J] squared coordinate differences and [T, J] joint distances, both in
        units of ``height``; NaN where either track misses the joint.

    Raises:
        InputError: shapes differ, or the height is not positive.
    """
    pred = np.asarray(pred, dtype=np.float64)
    truth = np.asarray(truth, dtype=np.float64)
    if pred.shape != truth.shape or pred.ndim != 3 or pred.shape[2] != 2:
        raise InputError(f"pose error: shape {truth.shape} of the truth does not match the prediction's {pred.shape}")
    if not height > 0:
        raise InputError(f"pose error: height must be positive, got {height}")
    diff = (pred - truth) / height  # [T, J, 2]
    return diff.reshape(len(diff), -1) ** 2, np.linalg.norm(diff, axis=-1)


def pck_hits(distance: np.ndarray, alpha: float) -> np.ndarray:
    """1.0 where a joint is closer than ``alpha`` heights to the truth, 0.0 where not, NaN where missing."""
    with np.errstate(invalid="ignore"):
        return np.where(np.isnan(distance), np.nan, (distance < alpha).astype(np.float64))


def pose_error(
    pred: np.ndarray, truth: np.ndarray, height: float, alphas: tuple[float, ...] = PCK_ALPHAS
) -> dict[str, float]:
    """The paper's pose error and its companions, joints missing in either track left out.

    Args:
        pred: [T, J, 2] pixels.
        truth: [T, J, 2] pixels.
        height: the target's body height in pixels.
        alphas: PCK thresholds in heights.

    Returns:
        ``mse``: mean over frames, joints and both coordinates of the squared height-normalised difference
        (height² units; reports show it x 10³); ``rmse_pct``: root mean squared joint distance in % of the
        height; ``pck_<alpha>``: share of joints closer than ``alpha`` heights.
    """
    squared, distance = pose_error_terms(pred, truth, height)
    out = {"mse": _nanmean(squared), "rmse_pct": float(np.sqrt(_nanmean(distance**2)) * 100.0)}
    for alpha in alphas:
        out[f"pck_{alpha:g}"] = _nanmean(pck_hits(distance, alpha))
    return out


def _nanmean(values: np.ndarray) -> float:
    values = np.asarray(values, dtype=np.float64)
    values = values[~np.isnan(values)]
    return float(values.mean()) if values.size else float("nan")


# The joint every root-aligned measure subtracts (the network's root, OpenPose's MidHip).
ROOT = "mid_hip"


def root_aligned(joints: np.ndarray, layout: JointLayout | str = "body15") -> np.ndarray:
    """Every joint relative to the same frame's root (``mid_hip``), the root itself left out.

    The pose without its placement: what the pose errors of ``clone retarget eval`` ("pose") and ``clone
    report`` (the primary row) compare.

    Args:
        joints: [T, J, 2] pixels, NaN where missing.
        layout: joint layout of ``joints`` (must have ``mid_hip``).

    Returns:
        [T, J - 1, 2] float64 offsets from the root, in the layout's joint order without the root; NaN where the
        joint or the root is missing.
    """
    layout = as_layout(layout)
    joints = check_joints(joints, layout, "root-aligned pose")
    root = layout.index(ROOT)
    return np.delete(joints - joints[:, root : root + 1], root, axis=1)  # [T, J - 1, 2]


def aligned_pose_error(
    pred: np.ndarray, truth: np.ndarray, height: float, layout: JointLayout | str = "body15",
    alphas: tuple[float, ...] = PCK_ALPHAS,
) -> dict[str, float]:
    """:func:`pose_error` of the root-aligned poses (:func:`root_aligned`): the pose error without placement.

    Args:
        pred: [T, J, 2] pixels.
        truth: [T, J, 2] pixels, the same layout.
        height: the target's body height in pixels.
        layout: joint layout of both.
        alphas: PCK thresholds in heights.
    """
    return pose_error(root_aligned(pred, layout), root_aligned(truth, layout), height, alphas)


def root_distance(
    pred: np.ndarray, truth: np.ndarray, height: float, layout: JointLayout | str = "body15"
) -> np.ndarray:
    """Placement error: the distance between the two tracks' roots (``mid_hip``) in every frame.

    Args:
        pred: [T, J, 2] pixels.
        truth: [T, J, 2] pixels, the same layout.
        height: the target's body height in pixels.
        layout: joint layout of both.

    Returns:
        [T] distances in units of ``height``; NaN where either root is missing.
    """
    layout = as_layout(layout)
    pred = check_joints(pred, layout, "root distance")
    truth = check_joints(truth, layout, "root distance")
    if pred.shape != truth.shape:
        raise InputError(f"root distance: shape {truth.shape} of the truth does not match the prediction's {pred.shape}")
    if not height > 0:
        raise InputError(f"root distance: height must be positive, got {height}")
    root = layout.index(ROOT)
    return np.linalg.norm(pred[:, root] - truth[:, root], axis=-1) / height


# The head points where the body faces: the nose lies in front of the neck.
FACING_JOINTS: tuple[str, str] = ("nose", "neck")


def facing_offset(joints: np.ndarray, height: float, layout: JointLayout | str = "body15") -> np.ndarray:
    """Which way a person faces in the image: the nose's horizontal offset from the neck.

    A body seen from its left (camera yaw > 0) faces image-left, its nose left of its neck (offset < 0); seen
    from its right, the offset is > 0; seen from the front or the back it is about 0. (The left-right order of
    the shoulders cannot tell the two sides apart: it is the same for every view within 90° of the front.)

    Args:
        joints: [T, J, 2] pixels, NaN where missing.
        height: the body height in pixels.
        layout: joint layout of ``joints`` (must have ``nose`` and ``neck``).

    Returns:
        [T] ``(x_nose - x_neck) / height``; NaN where either joint is missing.
    """
    layout = as_layout(layout)
    joints = check_joints(joints, layout, "facing")
    nose, neck = layout.indices(FACING_JOINTS)
    return (joints[:, nose, 0] - joints[:, neck, 0]) / height


def same_facing(
    pred: np.ndarray, truth: np.ndarray, pred_height: float, truth_height: float,
    layout: JointLayout | str = "body15", min_offset: float = 0.01,
) -> np.ndarray:
    """Per frame, whether ``pred`` faces the same side of the image as ``truth`` (:func:`facing_offset`).

    Args:
        pred: [T, J, 2] pixels.
        truth: [T, J, 2] pixels (may be another image; only signs are compared).
        pred_height: body height of ``pred`` in pixels.
        truth_height: body height of ``truth`` in pixels.
        layout: joint layout of both.
        min_offset: frames where the truth's offset is smaller than this (in heights: seen nearly from the
            front or the back, no side to face) are left out.

    Returns:
        [T] 1.0 same side, 0.0 the other side, NaN where the truth shows no side or a joint is missing.
    """
    mine = facing_offset(pred, pred_height, layout)
    theirs = facing_offset(truth, truth_height, layout)
    if mine.shape != theirs.shape:
        raise InputError(f"facing: {len(theirs)} frames of the truth, {len(mine)} of the prediction")
    with np.errstate(invalid="ignore"):
        clear = np.abs(theirs) >= min_offset
        same = (np.sign(mine) == np.sign(theirs)).astype(np.float64)
    return np.where(clear & ~np.isnan(mine), same, np.nan)
