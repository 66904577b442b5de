"""Evaluation metrics, silhouettes and `clone retarget eval` on a tiny world."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
import torch
from typer.testing import CliRunner

from clone.cli.main import app
from retarget.checkpoint import save_checkpoint
from retarget.evaluate import pose_errors, root_aligned, silhouette
from retarget.model import RetargetNet, variant_config
from retarget.preprocess import NormStats

TINY = (
    "bandai_namco/dataset-1/dataset-1_walk_normal_001.bvh.gz",
    "bandai_namco/dataset-1/dataset-1_bow_normal_001.bvh.gz",
    "bandai_namco/dataset-2/dataset-2_walk_normal_001.bvh.gz",
    "bandai_namco/dataset-2/dataset-2_walk_normal_002.bvh.gz",
)


def test_identical_poses_score_perfectly():
    joints = np.random.default_rng(0).uniform(0, 100, (10, 15, 2))
    scores = pose_errors(joints, joints, 100.0)
    assert scores == {"mse_x1e3": 0.0, "rmse_pct": 0.0, "pck_0.05": 1.0, "pck_0.1": 1.0}


def test_known_offset_gives_known_errors():
    truth = np.zeros((4, 15, 2))
    pred = truth + np.array([6.0, 8.0])  # every joint 10 px away
    scores = pose_errors(pred, truth, height=100.0)
    assert scores["rmse_pct"] == pytest.approx(10.0)
    assert scores["mse_x1e3"] == pytest.approx((0.06**2 + 0.08**2) / 2 * 1e3)
    assert scores["pck_0.05"] == 0.0 and scores["pck_0.1"] == 0.0  # 10 % is not within 10 %
    assert pose_errors(root_aligned(pred), root_aligned(truth), 100.0)["rmse_pct"] == 0.0


def test_silhouette_separated_vs_random():
    rng = np.random.default_rng(0)
    centres = np.array([[0.0, 0.0], [100.0, 0.0], [0.0, 100.0]])
    labels = np.repeat(np.arange(3), 20)
    clustered = centres[labels] + rng.normal(0, 1, (60, 2))
    assert silhouette(clustered, labels) > 0.95
    assert abs(silhouette(rng.normal(0, 1, (60, 2)), rng.integers(0, 3, 60))) < 0.1


def test_cli_eval_writes_table(shared_dir: Path, tmp_path: Path):
    mocap = tmp_path / "mocap"
    mocap.mkdir()
    for rel in TINY:
        shutil.copy(shared_dir / "mocap" / rel, mocap / Path(rel).name)
    torch.manual_seed(0)
    model = RetargetNet(variant_config("full"))
    stats = NormStats(np.zeros((15, 2)), np.full((15, 2), 50.0))
    weights = tmp_path / "w.pt"
    save_checkpoint(weights, model, stats)
    out = tmp_path / "eval"
    args = ["retarget", "eval", "--mocap", str(mocap), "--cache", str(tmp_path / "cache"), "--weights",
            str(weights), "--compare", f"again={weights}", "--pairs", "4", "--split", "train", "--out", str(out)]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    doc = json.loads((out / "eval.json").read_text())
    rows = set(doc["results"])
    assert {"ours (full)", "again", "global scaling (Everybody Dance Now)", "naive 2D FK (per-limb scaling)",
            "3D naive copy", "3D global scale"} <= rows
    assert "| ours (full) |" in (out / "eval.md").read_text()
    assert set(doc["silhouettes"]) == {"motion", "body", "view"}
    assert (out / "codes_view.png").is_file()
    again = CliRunner().invoke(app, args)
    assert again.exit_code == 2 and "already exists" in again.output
