"""`clone demo` end to end on a tiny configuration, its folder layout, and its folder rules."""

from __future__ import annotations

import json
import re

from typer.testing import CliRunner

import clone.demo
from clone.cli.main import app
from clone.demo import MARKER, PAIRS, DemoConfig, demo_motions
from clone.demo.config import shortened

# The shipped pairs on 64² videos, a 32² model trained for 3 s and 16 frames per pair: every stage runs.
TINY = DemoConfig(render_size=64, model_size=32, minutes=0.05, reference_frames=48, pairs=shortened(PAIRS, 16))


def test_shipped_motions_load():
    motions = demo_motions()
    assert motions["reference"].positions.shape == (458, 18, 3)
    assert motions["driver"].positions.shape == (215, 18, 3)
    assert {p.motion for p in PAIRS} <= set(motions)
    assert all(m.fps == 30.0 and m.name.startswith("CMU") for m in motions.values())


def test_tiny_demo_end_to_end(tmp_path, monkeypatch):
    monkeypatch.setattr(clone.demo, "QUICK", TINY)  # the command reads clone.demo.QUICK when it runs
    out = tmp_path / "demo"
    result = CliRunner().invoke(app, ["demo", "--quick", "--out", str(out), "--device", "cpu"])
    assert result.exit_code == 0, result.output
    assert f"report: {out / 'report.html'}" in result.output
    assert re.search(r"proportions: pose error [\d.]+ / [\d.]+ % of height \([\d.]+x\)", result.output)
    assert (out / MARKER).is_file() and (out / "ref_model.pt").is_file() and (out / "reference" / "frames").is_dir()
    record = json.loads((out / "demo.json").read_text())
    assert list(record["pairs"]) == [p.name for p in PAIRS]
    assert {"render", "train", "report view", "overview"} <= set(record["seconds"])
    for pair in PAIRS:
        folder = out / pair.name
        assert (folder / "driver" / "poses.npz").is_file() and (folder / "ground_truth" / "frames").is_dir()
        assert record["ground_truth_edge_px"][pair.name] >= TINY.edge_margin * TINY.render_size
        metrics = json.loads((folder / "report" / "metrics.json").read_text())
        assert list(metrics["methods"]) == ["global-scale", "retarget"]
        for summary in (m["summary"] for m in metrics["methods"].values()):
            assert 0.0 < summary["ssim_crop"] <= 1.0 and summary["pose_rmse_pct"] > 0.0
            assert summary["root_rmse_pct"] >= 0.0 and "facing_share" in summary and "stage_share" in summary
        assert record["pairs"][pair.name]["retarget"]["pose_rmse_pct"] == metrics["methods"]["retarget"]["summary"][
            "pose_rmse_pct"
        ]
    page = (out / "report.html").read_text()
    links = re.findall(r'(?:src|href)="([^"#]+)"', page)
    assert "view/report/side_by_side.mp4" in links and all((out / ln).is_file() for ln in links)
    assert all(f'id="pair-{p.name}"' in page for p in PAIRS)


def test_demo_refuses_a_folder_it_did_not_make(tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "keep.txt").write_text("user data")
    result = CliRunner().invoke(app, ["demo", "--quick", "--out", str(out)])
    assert result.exit_code == 2
    assert "not made by `clone demo`" in result.output
    assert (out / "keep.txt").read_text() == "user data"


def test_a_failed_demo_puts_the_earlier_one_back(tmp_path, monkeypatch):
    out = tmp_path / "demo"
    out.mkdir()
    (out / MARKER).write_text("earlier\n")
    (out / "report.html").write_text("earlier page")

    def broken(*args, **kwargs):
        raise RuntimeError("training failed")

    monkeypatch.setattr("clone.train_ref.train_reference", broken)
    try:
        clone.demo.run_demo(out, TINY)
    except RuntimeError as exc:
        assert "training failed" in str(exc)
    else:
        raise AssertionError("the demo should have failed")
    assert (out / "report.html").read_text() == "earlier page"
    assert [p.name for p in tmp_path.iterdir()] == ["demo"]  # no half-made folder left behind


def test_threads_option_sets_torch_threads_before_the_demo_runs(tmp_path, monkeypatch):
    import torch

    from pose_io.errors import InputError

    seen = []

    def stop(*args, **kwargs):
        seen.append(torch.get_num_threads())
        raise InputError("stopped here")

    before = torch.get_num_threads()
    monkeypatch.setattr(clone.demo, "run_demo", stop)
    try:
        for n in (1, 2):
            result = CliRunner().invoke(app, ["demo", "--out", str(tmp_path / "d"), "--device", "cpu", "--threads",
                                              str(n)])
            assert result.exit_code == 2 and "stopped here" in result.output
    finally:
        torch.set_num_threads(before)
    assert seen == [1, 2]
