"""`clone cartoon` through typer's CliRunner."""

import json

import pytest
from typer.testing import CliRunner

from clone.cli.main import app
from pose_io.readers import read_track
from pose_io.writers import write_track


@pytest.fixture(scope="module")
def driver_folder(driver, tmp_path_factory):
    return write_track(driver, tmp_path_factory.mktemp("driver") / "walker")


def test_writes_the_video_the_report_and_the_poses(driver, driver_folder, tmp_path):
    out = tmp_path / "toon.mp4"
    result = CliRunner().invoke(app, ["cartoon", str(driver_folder), "--character", "chibi", "--out", str(out),
                                      "--poses", str(tmp_path / "toon.npz"), "--device", "cpu"])
    assert result.exit_code == 0, result.output
    assert out.stat().st_size > 0
    report = json.loads((tmp_path / "toon.json").read_text())
    assert report["character"]["name"] == "chibi" and report["frames"] == len(driver)
    assert set(report["limb_error_pct"]) == {"network", "global_scale", "driver", "reference", "after_fix"}
    assert "global scaling" in result.output and "toon.json" in result.output
    poses = read_track(tmp_path / "toon.npz")
    assert len(poses) == len(driver) and poses.layout == "body15" and not poses.missing.any()


def test_a_json_character_a_chosen_yaw_and_a_named_report(driver_folder, tmp_path):
    spec = tmp_path / "giraffe.json"
    spec.write_text(json.dumps({"name": "giraffe", "head": 0.8, "torso": 1.6, "legs": 1.2}))
    out, report = tmp_path / "g.mp4", tmp_path / "measures" / "g.json"
    result = CliRunner().invoke(app, ["cartoon", str(driver_folder), "--character", str(spec), "--yaw", "-45",
                                      "--out", str(out), "--report", str(report), "--device", "cpu"])
    assert result.exit_code == 0, result.output
    data = json.loads(report.read_text())
    assert data["character"]["name"] == "giraffe" and data["view"] == "yaw -45"


def test_errors_are_one_line(driver_folder, tmp_path):
    runner = CliRunner()
    base = ["cartoon", str(driver_folder), "--device", "cpu"]
    bad = tmp_path / "bad.json"
    bad.write_text('{"legs": 0}')
    taken = tmp_path / "taken.mp4"
    taken.write_bytes(b"")
    cases = [
        (["--character", "giraffe", "--out", str(tmp_path / "a.mp4")], "not a preset"),
        (["--character", str(bad), "--out", str(tmp_path / "a.mp4")], "legs must be a number"),
        (["--character", "bighead", "--out", str(taken)], "already exists"),
        (["--character", "bighead", "--out", str(tmp_path / "a.gif")], ".mp4"),
        (["--character", "bighead", "--out", str(tmp_path / "a.mp4"), "--yaw", "120"], "--yaw"),
    ]
    for extra, message in cases:
        result = runner.invoke(app, [*base, *extra])
        assert result.exit_code == 2, result.output
        assert message in result.output and result.output.strip().count("\n") == 0, result.output
    assert not (tmp_path / "a.mp4").exists() and not (tmp_path / "a.json").exists()
