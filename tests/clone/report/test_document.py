"""metrics.json: plain, strict JSON holding every number of a report."""

from __future__ import annotations

import json

import numpy as np

from clone import metrics
from clone.report.document import METRICS_FORMAT, METRICS_VERSION, json_value, metrics_document, write_metrics
from tests.clone.report.helpers import make_methods


def test_json_value():
    value = {1: np.array([1.5, np.nan, np.inf]), "t": (np.int64(3), -np.inf, "x", None, True)}
    assert json_value(value) == {"1": [1.5, None, "inf"], "t": [3, "-inf", "x", None, True]}
    assert type(json_value(np.float32(0.5))) is float and type(json_value(np.int32(2))) is int


def test_metrics_document(tmp_path):
    methods, info, gt = make_methods(frames=6, with_frames=False)
    doc = metrics_document(methods, info, None)
    assert (doc["format"], doc["version"]) == (METRICS_FORMAT, METRICS_VERSION)
    assert doc["driver"] == {"source": "drv/poses.npz", "frames": 6, "fps": 30.0, "image_size": [64, 64],
                             "layout": "body15"}  # fmt: skip
    assert (
        doc["reference"] == "ref_model.pt" and doc["ground_truth"] is None and doc["driver_baseline"] is None
    )
    assert set(doc["metrics"]) == set(metrics.METRICS)
    assert list(doc["methods"]) == ["global-scale", "retarget"]
    assert set(doc["methods"]["retarget"]) == {"label", "layout", "summary", "per_frame", "details"}

    write_metrics(tmp_path / "m.json", methods, info, gt)
    written = json.loads((tmp_path / "m.json").read_text())
    assert written["ground_truth"] == {"poses": "gt/poses", "frames": "gt/frames"}
    assert written["methods"] == doc["methods"]  # the ground truth's sources change nothing else
