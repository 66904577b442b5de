"""`--refine-steps` of `clone drive`, `clone report` and `clone cartoon` reaches the retargeting network."""

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import clone.drive.poses
import clone.drive.run
import retarget.api
from clone.cli.main import app
from clone.drive.poses import move_onto_reference
from clone.drive.run import DriveResult
from clone.model.reference import load_reference_model
from pose_io.errors import InputError
from pose_io.readers import read_track
from pose_io.writers import write_track
from retarget.api import ReferenceCodes, load_retargeter
from retarget.inference.config import InferenceConfig
from tests.clone.train_ref.helpers import (  # noqa: F401 (_restore_threads is an autouse fixture)
    _restore_threads,
    figure_track,
    train_args,
    write_reference,
)


@pytest.fixture
def driver(tmp_path: Path) -> Path:
    return write_track(figure_track(30, width=160, height=120, scale=0.7, phase=5.0), tmp_path / "drv.npz")


@pytest.fixture(scope="module")
def model_path(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("ref")
    poses, frames = write_reference(folder / "ref", figure_track(24))
    result = CliRunner().invoke(app, train_args(poses, frames, folder / "ref.pt"))
    assert result.exit_code == 0, result.output
    return folder / "ref.pt"


def test_drive_poses_refine_or_not(driver: Path, model_path: Path) -> None:
    model = load_reference_model(model_path)
    track = read_track(driver).to_layout("body15")
    plain = move_onto_reference(track, model, "retarget", stage="raw", foot_lock=False, refine_steps=0)
    refined = move_onto_reference(track, model, "retarget", stage="raw", foot_lock=False)
    alone = load_retargeter(config=InferenceConfig(refine_steps=0))  # the network as its encoders give the codes
    expected = alone.retarget(track, ReferenceCodes.from_dict(model.reference_codes))
    np.testing.assert_allclose(plain.joints, expected.joints, atol=1e-2)
    assert np.abs(refined.joints - plain.joints).max() > 0.1  # refinement moved the poses


@pytest.mark.parametrize(("flag", "expected"), [((), None), (("--refine-steps", "0"), 0), (("--refine-steps", "5"), 5)])
def test_drive_and_report_pass_the_steps(flag, expected, driver, model_path, tmp_path, monkeypatch):
    seen = {}

    def fake_drive(path, out, **kwargs):
        seen["drive"] = kwargs["refine_steps"]
        return DriveResult(Path(out), 1, 30.0, (32, 32), kwargs["method"], None, 0.0)

    def fake_drive_poses(*args, **kwargs):
        seen["report"] = kwargs["refine_steps"]
        raise InputError("stopped here")

    monkeypatch.setattr(clone.drive.run, "drive", fake_drive)
    monkeypatch.setattr(clone.drive.poses, "drive_poses", fake_drive_poses)
    result = CliRunner().invoke(app, ["drive", str(driver), "--out", str(tmp_path / "o.mp4"), "--threads", "1",
                                      "--device", "cpu", *flag])
    assert result.exit_code == 0, result.output
    result = CliRunner().invoke(app, ["report", str(driver), "--out", str(tmp_path / "rep"), "--model", str(model_path),
                                      "--device", "cpu", *flag])
    assert result.exit_code == 2 and "stopped here" in result.output
    assert seen == {"drive": expected, "report": expected}


def test_cartoon_passes_the_steps(driver, tmp_path, monkeypatch):
    seen = {}

    def fake_load(weights=None, device="cpu", config=None, backend="torch"):
        seen["steps"] = None if config is None else config.refine_steps
        raise InputError("stopped here")

    monkeypatch.setattr(retarget.api, "load_retargeter", fake_load)
    for flag, expected in (((), None), (("--refine-steps", "0"), 0)):
        result = CliRunner().invoke(app, ["cartoon", str(driver), "--character", "bighead", "--out",
                                          str(tmp_path / "c.mp4"), "--device", "cpu", *flag])
        assert result.exit_code == 2 and "stopped here" in result.output
        assert seen["steps"] == expected
