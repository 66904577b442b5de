"""Scores of one case: known values, and what each alignment removes."""

from __future__ import annotations

import numpy as np
import pytest

from retarget.evaluate import case_scores, offset_aligned, pose_errors, root_aligned
from retarget.evaluate.scores import summarise
from retarget.network.preprocess import ROOT_INDEX


def test_identical_poses_score_perfectly() -> None:
    joints = np.random.default_rng(0).uniform(0, 100, (10, 15, 2))
    assert pose_errors(joints, joints, 100.0) == {"mse_x1e3": 0.0, "rmse_pct": 0.0, "pck_0.05": 1.0, "pck_0.1": 1.0,
                                                   "amplitude": 1.0}
    for scores in case_scores(joints, joints, 100.0).values():
        assert scores["mse_x1e3"] == 0.0 and scores["pck_0.05"] == 1.0


def test_known_displacements_give_known_errors() -> None:
    truth = np.zeros((4, 10, 2))
    pred = truth.copy()
    pred[:, :5] += [3.0, 4.0]  # half the joints 5 px away (5 % of a 100 px height)...
    pred[:, 5:] += [0.0, 12.0]  # ...the other half 12 px (12 %)
    scores = pose_errors(pred, truth, height=100.0)
    assert scores["mse_x1e3"] == pytest.approx((0.03**2 + 0.04**2 + 0.12**2) / 4 * 1e3)
    assert scores["rmse_pct"] == pytest.approx(np.sqrt((5.0**2 + 12.0**2) / 2))
    assert scores["pck_0.05"] == 0.0  # 5 % is not within 5 %
    assert scores["pck_0.1"] == 0.5
    # The same displacement in a twice as tall target is half as large.
    assert pose_errors(pred, truth, height=200.0)["rmse_pct"] == pytest.approx(scores["rmse_pct"] / 2)


def test_alignments_separate_placement_from_pose() -> None:
    rng = np.random.default_rng(1)
    truth = rng.uniform(100, 400, (8, 15, 2))
    moved = truth + [30.0, -20.0]  # the right motion in the wrong place
    scores = case_scores(moved, truth, 300.0)
    assert scores["pose"]["mse_x1e3"] == pytest.approx(0.0, abs=1e-12)
    assert scores["with_root"]["mse_x1e3"] == pytest.approx(0.0, abs=1e-12)
    assert scores["placed"]["rmse_pct"] == pytest.approx(100 * np.hypot(30, 20) / 300)
    # A pose scaled by 1.1 about MidHip: every root-relative joint is 10 % of its distance off.
    root = truth[:, ROOT_INDEX : ROOT_INDEX + 1]
    scaled = root + 1.1 * (truth - root)
    local = np.delete(truth - root, ROOT_INDEX, axis=1)
    expected = 100 * np.sqrt(np.mean(np.sum((0.1 * local / 300.0) ** 2, axis=-1)))
    assert case_scores(scaled, truth, 300.0)["pose"]["rmse_pct"] == pytest.approx(expected)
    assert root_aligned(truth).shape == (8, 14, 2)
    assert np.allclose(offset_aligned(moved, truth), truth)


def test_summary_is_the_mean_and_its_standard_error() -> None:
    rng = np.random.default_rng(2)
    truth = rng.uniform(100, 400, (6, 15, 2))
    cases = [case_scores(truth + shift, truth, 300.0) for shift in ([0.0, 0.0], [3.0, 0.0], [0.0, 9.0])]
    summary = summarise(cases)
    placed = np.array([c["placed"]["rmse_pct"] for c in cases])
    assert summary["placed"]["rmse_pct"] == pytest.approx(placed.mean())
    assert summary["placed"]["rmse_pct_se"] == pytest.approx(placed.std(ddof=1) / np.sqrt(3))
    assert summary["pose"]["mse_x1e3_se"] == pytest.approx(0.0, abs=1e-12)  # a shift leaves the pose alone
    assert summarise(cases[:1])["placed"]["rmse_pct_se"] == 0.0
