"""`clone retarget apply` and `clone retarget train` through typer's CliRunner."""

import shutil

import pytest
from typer.testing import CliRunner

from clone.cli.main import app
from pose_io.readers import read_track
from retarget import api


@pytest.fixture(scope="module")
def inputs(shared_dir):
    return {
        "weights": shared_dir / "official_2dmr" / "weights" / "pretrained_full.pth",
        "tall": shared_dir / "openpose_examples" / "tall_man",
        "small": shared_dir / "openpose_examples" / "small_man",
    }


def test_apply_writes_an_openpose_folder_and_a_preview(inputs, tmp_path):
    out, preview = tmp_path / "moved", tmp_path / "moved.mp4"
    result = CliRunner().invoke(app, [
        "retarget", "apply", str(inputs["tall"]), "--skeleton", str(inputs["small"]), "--out", str(out),
        "--preview", str(preview), "--weights", str(inputs["weights"]), "--size", "720x720", "--device", "cpu",
    ])
    assert result.exit_code == 0, result.output
    track = read_track(out)
    assert len(track) == 135 and track.layout == "body15" and track.image_size == (720, 720)
    assert preview.stat().st_size > 0


def test_apply_errors_are_one_line(inputs, tmp_path, monkeypatch):
    runner = CliRunner()
    taken = tmp_path / "taken"
    taken.mkdir()
    base = ["retarget", "apply", str(inputs["tall"]), "--skeleton", str(inputs["small"])]
    result = runner.invoke(app, [*base, "--out", str(taken), "--weights", str(inputs["weights"])])
    assert result.exit_code == 2 and "already exists" in result.output
    monkeypatch.setattr(api, "PACKAGED_WEIGHTS", tmp_path / "clone2d_full.pt")
    result = runner.invoke(app, [*base, "--out", str(tmp_path / "o")])
    assert result.exit_code == 2 and "no trained retargeting weights are shipped yet" in result.output
    short = tmp_path / "short"
    short.mkdir()
    for f in sorted(inputs["small"].glob("*.json"))[:10]:
        shutil.copy(f, short)
    result = runner.invoke(app, ["retarget", "apply", str(short), "--skeleton", str(inputs["small"]),
                                 "--out", str(tmp_path / "o"), "--weights", str(inputs["weights"])])
    assert result.exit_code == 2 and "10 frames; the retargeting network needs at least 16" in result.output
    assert str(short) in result.output
    assert not (tmp_path / "o").exists()


def test_train_errors_are_one_line(tmp_path):
    runner = CliRunner()
    out = tmp_path / "r.pt"
    out.write_bytes(b"")
    result = runner.invoke(app, ["retarget", "train", "--mocap", str(tmp_path), "--out", str(out)])
    assert result.exit_code == 2 and "pass --resume" in result.output
    result = runner.invoke(app, ["retarget", "train", "--mocap", str(tmp_path), "--out", str(tmp_path / "n.pt"),
                                 "--variant", "huge"])
    assert result.exit_code == 2 and "unknown network variant 'huge'" in result.output
    result = runner.invoke(app, ["retarget", "train", "--mocap", str(tmp_path / "none"),
                                 "--out", str(tmp_path / "n.pt"), "--device", "cpu"])
    assert result.exit_code == 2 and "no such folder" in result.output
