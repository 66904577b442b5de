"""metrics.json: every number of a report as strict JSON (no NaN or Infinity literals).

Layout: ``format`` and ``version``; ``driver`` (source, frames, fps, image size, layout); ``reference``;
``ground_truth`` (its sources, or null); ``metrics`` (label, unit, better direction, display scale and
meaning of every measure); ``methods`` (per method: label, layout, summary, per-frame curves, details);
``driver_baseline`` (the driver measured against itself, or null).
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from clone.metrics import METRICS, Scores
from clone.report.results import DriverInfo, GroundTruth, MethodResult

METRICS_FORMAT = "clone2d-report-metrics"
# 2: the pose error, the paper's MSE and PCK compare MidHip-aligned poses (placement is its own measure,
# root_rmse_pct); facing_share and stage_share are new.
METRICS_VERSION = 2

_NOTES = (
    "per_frame arrays have one value per driver frame; null = no value in that frame (e.g. no ankle in "
    "contact); \"inf\" = infinite (PSNR of identical frames). Units: see 'metrics'."
)


def json_value(value: object) -> object:
    """Plain JSON: mappings to dicts with string keys, arrays to lists, NaN to null, +-inf to "inf" / "-inf".

    Args:
        value: nested mappings, sequences, numpy arrays and scalars.

    Returns:
        The same data made of dict, list, str, int, float (finite), bool and None.
    """
    if isinstance(value, Mapping):
        return {str(k): json_value(v) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        return [json_value(v) for v in value.tolist()]
    if isinstance(value, (list, tuple)):
        return [json_value(v) for v in value]
    if isinstance(value, (float, np.floating)):
        value = float(value)
        if math.isnan(value):
            return None
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return value
    if isinstance(value, np.integer):
        return int(value)
    return value


def _scores_json(scores: Scores) -> dict[str, object]:
    return {"summary": scores.summary, "per_frame": scores.per_frame, "details": scores.details}


def _metric_definitions() -> dict[str, dict[str, object]]:
    """Label, unit, better direction, display scale and meaning of every measure."""
    return {
        k: {
            "label": m.label,
            "unit": m.unit,
            "better": m.better,
            "display_scale": m.scale,
            "meaning": m.meaning,
        }
        for k, m in METRICS.items()
    }


def metrics_document(
    methods: Mapping[str, MethodResult], driver: DriverInfo, gt: GroundTruth | None
) -> dict[str, object]:
    """The content of metrics.json, JSON-ready (NaN -> null, inf -> "inf").

    Args:
        methods: name -> result, in column order.
        driver: what drove the reference.
        gt: the ground truth, if any.
    """
    track = driver.poses
    doc = {
        "format": METRICS_FORMAT,
        "version": METRICS_VERSION,
        "notes": _NOTES,
        "driver": {
            "source": driver.source,
            "frames": track.num_frames,
            "fps": track.fps,
            "image_size": list(track.image_size),
            "layout": track.layout,
        },
        "reference": driver.reference,
        "ground_truth": None if gt is None else {"poses": gt.poses_source, "frames": gt.frames_source},
        "metrics": _metric_definitions(),
        "methods": {
            name: {"label": m.label, "layout": m.poses.layout, **_scores_json(m.scores)}
            for name, m in methods.items()
        },
        "driver_baseline": None if driver.scores is None else _scores_json(driver.scores),
    }
    return json_value(doc)  # type: ignore[return-value]


def write_metrics(
    path: Path, methods: Mapping[str, MethodResult], driver: DriverInfo, gt: GroundTruth | None
) -> None:
    """Write ``metrics_document`` to ``path`` as strict JSON (a NaN that slipped through raises ValueError)."""
    with open(path, "w", encoding="utf-8") as f:
        json.dump(metrics_document(methods, driver, gt), f, indent=1, allow_nan=False)
