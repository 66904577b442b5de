import json

from typer.testing import CliRunner

from clone.cli.main import app
from clone.demo import MARKER, demo_motions


def test_shipped_motions_load():
    motions = demo_motions()
    assert motions["reference"].positions.shape == (458, 18, 3)
    assert motions["driver"].positions.shape == (215, 18, 3)


def test_quick_demo_end_to_end(tmp_path):
    out = tmp_path / "demo"
    result = CliRunner().invoke(app, ["demo", "--quick", "--minutes", "0.15", "--out", str(out), "--device", "cpu"])
    assert result.exit_code == 0, result.output
    metrics = json.loads((out / "report" / "metrics.json").read_text())
    assert set(metrics["methods"]) >= {"retarget", "global-scale"}
    for method in ("retarget", "global-scale"):
        summary = metrics["methods"][method]["summary"]
        assert 0.0 < summary["ssim"] <= 1.0 and summary["pose_rmse_pct"] > 0.0
    assert (out / "report" / "report.html").is_file() and (out / "report" / "side_by_side.mp4").stat().st_size > 0
    assert (out / "ground_truth" / "frames").is_dir() and (out / MARKER).is_file()


def test_demo_refuses_a_folder_it_did_not_make(tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "keep.txt").write_text("user data")
    result = CliRunner().invoke(app, ["demo", "--quick", "--out", str(out)])
    assert result.exit_code == 2
    assert "not made by `clone demo`" in result.output
    assert (out / "keep.txt").read_text() == "user data"
