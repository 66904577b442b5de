"""`clone retarget apply` and `clone retarget train` through typer's CliRunner.

The inputs are OpenPose folders of people the tests build; apply runs with the weights shipped in the package.
"""

import shutil

import pytest
from typer.testing import CliRunner

from clone.cli.main import app
from pose_io.readers import read_track
from pose_io.writers import write_track
from retarget import api
from tests.figures import tall_and_small

FRAMES = 75


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("people")
    people = tall_and_small(FRAMES)
    return {
        "weights": api.PACKAGED_WEIGHTS,
        "tall": write_track(people["tall"], folder / "tall_man"),
        "small": write_track(people["small"], folder / "small_man"),
    }


def test_apply_writes_an_openpose_folder_and_a_preview(inputs, tmp_path):
    out, preview = tmp_path / "moved", tmp_path / "moved.mp4"
    result = CliRunner().invoke(app, [
        "retarget", "apply", str(inputs["tall"]), "--skeleton", str(inputs["small"]), "--out", str(out),
        "--preview", str(preview), "--weights", str(inputs["weights"]), "--size", "720x720", "--device", "cpu",
    ])
    assert result.exit_code == 0, result.output
    track = read_track(out)
    assert len(track) == FRAMES and track.layout == "body15" and track.image_size == (720, 720)
    assert preview.stat().st_size > 0


def test_apply_uses_the_packaged_weights_by_default(inputs, tmp_path):
    out = tmp_path / "moved.npz"
    result = CliRunner().invoke(app, ["retarget", "apply", str(inputs["tall"]), "--skeleton", str(inputs["small"]),
                                      "--out", str(out), "--device", "cpu"])
    assert result.exit_code == 0, result.output
    assert str(out) in result.output.replace("\n", "")
    track = read_track(out)
    assert len(track) == FRAMES and track.layout == "body15" and not track.missing.any()


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
    for f in sorted(inputs["small"].glob("*_keypoints.json"))[:10]:  # not the clone2d_track.json sidecar
        shutil.copy(f, short)
    result = runner.invoke(app, ["retarget", "apply", str(short), "--skeleton", str(inputs["small"]),
                                 "--out", str(tmp_path / "o"), "--weights", str(inputs["weights"])])
    need = api.load_retargeter(inputs["weights"]).min_frames
    assert result.exit_code == 2 and f"10 frames; the retargeting network needs at least {need}" in result.output
    assert str(short) in result.output
    assert not (tmp_path / "o").exists()


def test_apply_refine_steps(inputs, tmp_path):
    runner = CliRunner()
    base = ["retarget", "apply", str(inputs["tall"]), "--skeleton", str(inputs["small"]), "--size", "720x720",
            "--weights", str(inputs["weights"]), "--device", "cpu"]  # fmt: skip
    result = runner.invoke(app, [*base, "--out", str(tmp_path / "a"), "--refine-steps", "-1"])
    assert result.exit_code == 2 and "--refine-steps" in result.output
    assert not (tmp_path / "a").exists()
    npz = ["retarget", "apply", str(inputs["tall"]), "--skeleton", str(inputs["small"]), "--size", "720x720",
           "--weights", str(inputs["weights"].with_suffix(".npz")), "--no-foot-lock"]  # fmt: skip
    outs = {}
    for name, command in (("plain", [*base, "--refine-steps", "0", "--backend", "numpy"]), ("refined", base),
                          ("torch refined", [*base, "--backend", "torch", "--refine-steps", "3"]),
                          ("numpy refined", [*base, "--backend", "numpy", "--refine-steps", "3"]),
                          ("export refined", [*npz, "--refine-steps", "3"])):  # fmt: skip
        result = runner.invoke(app, [*command, "--out", str(tmp_path / f"{name}.npz"), "--no-foot-lock"])
        assert result.exit_code == 0, result.output
        outs[name] = read_track(tmp_path / f"{name}.npz").joints
    assert outs["plain"].shape == outs["refined"].shape
    assert abs(outs["plain"] - outs["refined"]).max() > 0.5  # pixels: the refined codes decode other poses
    # three steps on either backend, or from the export alone: the same poses
    for name in ("numpy refined", "export refined"):
        assert abs(outs[name] - outs["torch refined"]).max() < 2e-3, name


def test_train_errors_are_one_line(tmp_path):
    runner = CliRunner()
    out = tmp_path / "r.pt"
    out.write_bytes(b"")
    result = runner.invoke(app, ["retarget", "train", "--mocap", str(tmp_path), "--out", str(out)])
    assert result.exit_code == 2 and "pass --resume" in result.output
    result = runner.invoke(app, ["retarget", "train", "--mocap", str(tmp_path), "--out", str(tmp_path / "n.pt"),
                                 "--variant", "huge"])
    assert result.exit_code == 2 and "'huge'; valid: full, skeleton, view" in result.output  # typer checks the choice
    result = runner.invoke(app, ["retarget", "train", "--mocap", str(tmp_path / "none"),
                                 "--out", str(tmp_path / "n.pt"), "--device", "cpu"])
    assert result.exit_code == 2 and "no such folder" in result.output
    result = runner.invoke(app, ["retarget", "train", "--mocap", str(tmp_path), "--out", str(tmp_path / "n.pt"),
                                 "--best", str(out)])
    assert result.exit_code == 2 and "--best" in result.output and "exists" in result.output
    assert out.read_bytes() == b""  # untouched
    result = runner.invoke(app, ["retarget", "train", "--mocap", str(tmp_path), "--out", str(tmp_path / "n.pt"),
                                 "--best", str(tmp_path / "n.pt")])
    assert result.exit_code == 2 and "is --out" in result.output
    result = runner.invoke(app, ["retarget", "train", "--mocap", str(tmp_path), "--out", str(tmp_path / "n.pt"),
                                 "--average", str(out)])
    assert result.exit_code == 2 and "--average" in result.output and "exists" in result.output
    result = runner.invoke(app, ["retarget", "train", "--mocap", str(tmp_path), "--out", str(tmp_path / "n.pt"),
                                 "--best", str(tmp_path / "b.pt"), "--average", str(tmp_path / "b.pt")])
    assert result.exit_code == 2 and "is --out or --best" in result.output
    result = runner.invoke(app, ["retarget", "train", "--mocap", str(tmp_path), "--out", str(tmp_path / "n.pt"),
                                 "--average-from", "3"])
    assert result.exit_code == 2 and "needs --average" in result.output
    assert out.read_bytes() == b"" and not (tmp_path / "b.pt").exists() and not (tmp_path / "n.pt").exists()
