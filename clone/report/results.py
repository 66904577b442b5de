"""What a report compares: the driven methods, the driver and the ground truth, and how their numbers read.

Shared by the page, the plots, the stills and metrics.json: the result types, the names of the files in a
report folder, one colour per method, which method is better at a measure and how a value is printed.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from clone.metrics import METRICS, Scores
from pose_io.track import PoseTrack

PAGE = "report.html"
VIDEO = "side_by_side.mp4"
METRICS_FILE = "metrics.json"
CURVES = "curves.png"
SUMMARY = "summary.png"

# One colour per column of the report (driver, then the methods in order, then the ground truth).
_PALETTE = ("#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#e377c2")


@dataclass(frozen=True, eq=False)
class MethodResult:
    """One way of driving the reference, as a report shows it.

    Attributes:
        label: column title, e.g. ``"Retargeted"``.
        poses: the driven poses, in the same image as the reference's poses.
        scores: its measures (``clone.metrics``).
        stills: frame index -> [H, W, 3] uint8 RGB generated frame, for the still images.
        still_poses: frame index -> [J, 2] the driven pose in that frame's pixels (drawn over the still),
            in ``poses.layout``; missing indices are drawn without a skeleton.
        description: one sentence on how the method works, shown on the page.
    """

    label: str
    poses: PoseTrack
    scores: Scores
    stills: Mapping[int, np.ndarray] = field(default_factory=dict)
    still_poses: Mapping[int, np.ndarray] = field(default_factory=dict)
    description: str = ""


@dataclass(frozen=True, eq=False)
class DriverInfo:
    """What drove the reference.

    Attributes:
        poses: the driver's pose track.
        source: where it was read from, as the user gave it.
        reference: the reference model, as the user gave it.
        scores: the driver's own measures (its own height and limb lengths), shown as a grey baseline column.
    """

    poses: PoseTrack
    source: str
    reference: str
    scores: Scores | None = None


@dataclass(frozen=True, eq=False)
class GroundTruth:
    """The reference really performing the driver's motion, when it exists.

    Attributes:
        poses_source: where its poses were read from, or None.
        frames_source: where its frames were read from, or None.
        stills: frame index -> [H, W, 3] uint8 RGB true frame, in the generated frames' pixels.
        still_poses: frame index -> [J, 2] true pose in those pixels.
        layout: layout of ``still_poses``.
    """

    poses_source: str | None = None
    frames_source: str | None = None
    stills: Mapping[int, np.ndarray] = field(default_factory=dict)
    still_poses: Mapping[int, np.ndarray] = field(default_factory=dict)
    layout: str = "body15"


def method_colors(methods: Mapping[str, MethodResult]) -> dict[str, str]:
    """Method name -> its colour (hex), the same in the page and the plots; the first colour is the driver's."""
    return {name: _PALETTE[(i + 1) % len(_PALETTE)] for i, name in enumerate(methods)}


def summary_keys(methods: Mapping[str, MethodResult]) -> list[str]:
    """The measures at least one method has a summary value of, in ``clone.metrics.METRICS`` order."""
    return [k for k in METRICS if any(k in m.scores.summary for m in methods.values())]


def format_value(value: float | None, scale: float = 1.0) -> str:
    """A measure as the page prints it: ``value * scale`` to about 3 digits, "–" for none, "∞" for infinite.

    Args:
        value: the value in its stored unit, None or NaN when there is none.
        scale: display scale of the measure (``clone.metrics.MetricInfo.scale``).
    """
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "–"
    if math.isinf(value):
        return "∞" if value > 0 else "−∞"
    v = value * scale
    if abs(v) >= 100:
        return f"{v:.1f}"
    return f"{v:.3g}" if abs(v) >= 0.001 or v == 0 else f"{v:.2e}"


def best_methods(methods: Mapping[str, MethodResult], key: str) -> set[str]:
    """The methods with the better value of summary ``key`` (see :func:`best_of`)."""
    return best_of({n: m.scores.summary.get(key, float("nan")) for n, m in methods.items()}, key)


def best_of(values: Mapping[str, float | None], key: str) -> set[str]:
    """The names whose value of measure ``key`` is the better one.

    Args:
        values: name -> value (None or NaN: no value).
        key: a key of ``clone.metrics.METRICS``, which says which direction is better.

    Returns:
        Empty when all are equal, fewer than two have a value, or the measure has no better direction.
    """
    better = METRICS[key].better
    if better is None:
        return set()
    values = {n: float(v) for n, v in values.items() if v is not None and not math.isnan(float(v))}
    if len(values) < 2 or len(set(values.values())) == 1:
        return set()
    target = min(values.values()) if better == "lower" else max(values.values())
    return {n for n, v in values.items() if v == target}
