"""Scores of one case against its ground truth, under each alignment, and their summary over cases."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from pose_io.compare import pose_error, root_aligned
from pose_io.measures import amplitude_ratio

METRICS: tuple[str, ...] = ("mse_x1e3", "rmse_pct", "pck_0.05", "pck_0.1", "amplitude")
ALIGNMENTS: tuple[str, ...] = ("pose", "with_root", "placed")

CaseScores = dict[str, dict[str, float]]  # alignment -> metric -> value


def pose_errors(pred: np.ndarray, truth: np.ndarray, height: float) -> dict[str, float]:
    """The paper's error and its companions for one case.

    Args:
        pred: [T, J, 2] predicted pixels.
        truth: [T, J, 2] true pixels.
        height: the target's height in pixels.

    Returns:
        ``mse_x1e3``: mean over frames, joints and coordinates of the squared height-normalised difference,
        x 1000; ``rmse_pct``: root mean squared joint distance in % of the height; ``pck_0.05``, ``pck_0.1``:
        share of joints closer than that share of the height; ``amplitude``: the prediction's range of
        motion over the truth's (:func:`pose_io.measures.amplitude_ratio`; 1 = neither damped nor exaggerated).
    """
    scores = pose_error(pred, truth, height, (0.05, 0.1))
    return {
        "mse_x1e3": scores["mse"] * 1e3,
        "rmse_pct": scores["rmse_pct"],
        "pck_0.05": scores["pck_0.05"],
        "pck_0.1": scores["pck_0.1"],
        "amplitude": amplitude_ratio(pred, height, truth, height),
    }


def offset_aligned(pred: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """[T, J, 2] ``pred`` moved by the one translation that brings it closest to ``truth`` (least squares)."""
    return pred + (truth - pred).reshape(-1, 2).mean(axis=0)


def case_scores(pred: np.ndarray, truth: np.ndarray, height: float) -> CaseScores:
    """:func:`pose_errors` of [T, 15, 2] body15 ``pred`` vs ``truth`` under every alignment of :data:`ALIGNMENTS`.

    "pose" compares the root-aligned poses (:func:`pose_io.compare.root_aligned`, MidHip subtracted and left
    out), the same definition as the primary pose row of ``clone report``.
    """
    return {
        "pose": pose_errors(root_aligned(pred), root_aligned(truth), height),
        "with_root": pose_errors(offset_aligned(pred, truth), truth, height),
        "placed": pose_errors(pred, truth, height),
    }


def summarise(scores: Sequence[CaseScores]) -> dict[str, dict[str, float]]:
    """Means over cases of :func:`case_scores`: alignment -> ``{metric: mean, metric + "_se": standard error}``.

    The standard error is 0 for a single case.
    """
    out: dict[str, dict[str, float]] = {}
    for align in ALIGNMENTS:
        entry: dict[str, float] = {}
        for metric in METRICS:
            entry[metric], entry[metric + "_se"] = mean_se(np.array([s[align][metric] for s in scores]))
        out[align] = entry
    return out


def mean_se(values: np.ndarray) -> tuple[float, float]:
    """The mean of [N] values and its standard error (0 for a single value; both NaN for none)."""
    if not len(values):
        return float("nan"), float("nan")
    se = float(values.std(ddof=1) / np.sqrt(len(values))) if len(values) > 1 else 0.0
    return float(values.mean()), se
