"""`clone report` end to end, through the library and through the command line."""

from __future__ import annotations

import importlib.util
import json

import numpy as np
from typer.testing import CliRunner

from clone import metrics
from clone.cli.main import app
from clone.report.panels import caption_height
from clone.report.run import REPORT_METHODS, make_report
from tests.clone.report.helpers import SIZE, T, walk, write_gt

# pose consistency is measured where MediaPipe is installed (the extract extra)
HAS_MEDIAPIPE = importlib.util.find_spec("mediapipe") is not None
CONSISTENCY = {"consistency_pck", "consistency_median_pct"}


def test_make_report_end_to_end(tmp_path, tiny_models):
    from pose_io.video import read_frames
    from pose_io.writers import write_track

    model_path, weights = tiny_models
    driver = write_track(walk(T, 0.8), tmp_path / "driver.npz")
    gt_poses, gt_frames = write_gt(tmp_path)
    run = make_report(driver, tmp_path / "rep", model_path=model_path, gt_poses=gt_poses,
                      gt_frames=gt_frames, weights=weights)  # fmt: skip
    assert run.page.is_file() and run.frames == T
    assert set(run.summary) == {"global-scale", "retarget"}
    assert list(run.summary) == list(REPORT_METHODS)  # in column order
    for summary in run.summary.values():
        expected = set(metrics.METRICS) - (set() if HAS_MEDIAPIPE else CONSISTENCY)
        assert set(summary) == expected  # every measure, ground-truth ones included
        assert 0.0 <= summary["ssim"] <= 1.0 and np.isfinite(summary["psnr"])
    video = read_frames(tmp_path / "rep" / "side_by_side.mp4")
    # driver | global scaling | retargeted | ground truth: the 32² canvas shown at 256 rows under a caption
    assert video.num_frames == T and video.size == (4 * 256, 256 + caption_height(256))
    doc = json.loads((tmp_path / "rep" / "metrics.json").read_text())
    assert doc["ground_truth"] == {"poses": str(gt_poses), "frames": str(gt_frames)}
    assert doc["driver_baseline"]["summary"]["limb_error_pct"] >= 0.0


def test_cli_report_and_ground_truth_mismatches(tmp_path, tiny_models):
    from pose_io.writers import write_track

    model_path, weights = tiny_models
    driver = write_track(walk(T, 0.8), tmp_path / "driver.npz")
    runner = CliRunner()
    base = ["report", str(driver), "--model", str(model_path), "--weights", str(weights), "--device", "cpu"]

    short = tmp_path / "short"
    short.mkdir()
    poses, frames = write_gt(short, frames=T - 2)
    result = runner.invoke(app, [*base, "--out", str(tmp_path / "a"), "--gt-frames", str(frames)])
    assert result.exit_code == 2 and f"{T - 2} ground-truth frames, the driver has {T}" in result.output
    result = runner.invoke(app, [*base, "--out", str(tmp_path / "a"), "--gt-poses", str(poses)])
    assert result.exit_code == 2 and f"have {T - 2} frames, the driver has {T}" in result.output
    big = tmp_path / "big"
    big.mkdir()
    _, frames = write_gt(big, size=SIZE + 16)
    result = runner.invoke(app, [*base, "--out", str(tmp_path / "a"), "--gt-frames", str(frames)])
    assert (
        result.exit_code == 2
        and "ground-truth frames are 80x80, the reference model's frames are 64x64" in (result.output)
    )
    assert not (tmp_path / "a").exists()

    result = runner.invoke(app, [*base, "--out", str(tmp_path / "a")])
    assert result.exit_code == 0, result.output
    assert "wrote" in result.output and (tmp_path / "a" / "report.html").is_file()
    doc = json.loads((tmp_path / "a" / "metrics.json").read_text())
    assert doc["ground_truth"] is None and "ssim" not in doc["methods"]["retarget"]["summary"]
    summary = doc["methods"]["retarget"]["summary"]
    # measured without ground truth: flicker, and what MediaPipe sees in the frames; no ratio to a truth
    assert summary["flicker"] >= 0.0 and ("consistency_pck" in summary) == HAS_MEDIAPIPE
    assert "flicker_ratio" not in summary
    result = runner.invoke(app, [*base, "--out", str(tmp_path / "a")])
    assert result.exit_code == 2 and "--overwrite" in result.output
    result = runner.invoke(app, [*base, "--out", str(tmp_path / "c"), "--no-consistency"])
    assert result.exit_code == 0, result.output
    summary = json.loads((tmp_path / "c" / "metrics.json").read_text())["methods"]["retarget"]["summary"]
    assert "consistency_pck" not in summary and "flicker" in summary

    # with ground truth, the printed table leads with the MidHip-aligned pose error, as the page does
    good = tmp_path / "good"
    good.mkdir()
    poses, frames = write_gt(good)
    result = runner.invoke(app, [*base, "--out", str(tmp_path / "b"), "--gt-poses", str(poses), "--gt-frames",
                                 str(frames)], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    pose_row = result.output.index(metrics.METRICS["pose_rmse_pct"].label)
    assert pose_row < result.output.index(metrics.METRICS["limb_error_pct"].label)
    assert metrics.METRICS["psnr_background"].label in result.output
