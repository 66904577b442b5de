"""`clone drive --foot-lock/--no-foot-lock` reaches ``clone.drive.run.drive``; ``drive_poses`` honours it."""

from pathlib import Path

import pytest
from typer.testing import CliRunner

import clone.drive.run
from clone.cli.main import app
from clone.drive.run import DriveResult


@pytest.mark.parametrize(("flag", "expected"), [((), True), (("--foot-lock",), True), (("--no-foot-lock",), False)])
def test_drive_option_is_parsed(flag, expected, tmp_path, monkeypatch):
    seen = {}

    def fake_drive(driver, out, **kwargs):
        seen.update(kwargs)
        return DriveResult(Path(out), 1, 30.0, (32, 32), kwargs["method"], None, 0.0)

    monkeypatch.setattr(clone.drive.run, "drive", fake_drive)
    result = CliRunner().invoke(app, ["drive", str(tmp_path / "drv.npz"), "--out", str(tmp_path / "o.mp4"),
                                      "--threads", "1", "--device", "cpu", *flag])
    assert result.exit_code == 0, result.output
    assert seen["foot_lock"] is expected
