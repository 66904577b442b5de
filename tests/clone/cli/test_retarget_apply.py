"""`clone retarget apply`: the torch-free path, and many clips in one run (a folder or several inputs).

Packaged weights (their numpy export sits beside them); tracks built in tmp_path.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from clone.cli.main import app
from pose_io.readers import read_track
from pose_io.writers import write_track
from tests.figures import walking_figure

REPO = Path(__file__).resolve().parents[3]
PX = 2e-3  # a clip batched with others vs alone: float32 rounding only


@pytest.fixture
def clips(tmp_path) -> dict[str, Path]:
    """Four driver clips of different lengths in ``clips/`` and a reference."""
    folder = tmp_path / "clips"
    folder.mkdir()
    paths = {name: write_track(walking_figure(n, seed=n), folder / f"{name}.npz")
             for name, n in (("walk", 40), ("long", 300), ("short", 16), ("mid", 75))}  # fmt: skip
    paths["reference"] = write_track(walking_figure(64, height=260.0, legs=0.42, seed=9), tmp_path / "ref.npz")
    return paths


def _apply(*args: object) -> object:
    return CliRunner().invoke(app, ["retarget", "apply", *map(str, args), "--device", "cpu", "--threads", "1"])


def _one_error_line(result) -> str:
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert result.exit_code == 2 and len(lines) == 1 and lines[0].startswith("error: "), result.output
    return lines[0]


def test_apply_runs_without_importing_torch(clips, tmp_path):
    """The packaged weights have an up-to-date .npz: apply, motion-code refinement included, never imports torch
    (-X importtime lists every import)."""
    out = tmp_path / "moved.npz"
    cmd = [sys.executable, "-X", "importtime", "-m", "clone", "retarget", "apply", str(clips["walk"]),
           "--skeleton", str(clips["reference"]), "--out", str(out), "--threads", "1"]
    proc = subprocess.run(cmd, cwd=REPO, capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr[-2000:]
    imported = [line.rsplit("|", 1)[-1].strip() for line in proc.stderr.splitlines() if line.startswith("import time")]
    assert "retarget.network.numpy_net" in imported and not [m for m in imported if m.split(".")[0] == "torch"]
    assert len(read_track(out)) == 40
    out.unlink()
    proc = subprocess.run([*cmd, "--backend", "torch"], cwd=REPO, capture_output=True, text=True, check=False)
    assert proc.returncode == 0 and "| torch" in proc.stderr  # the check above can see torch


def test_backends_write_the_same_poses(clips, tmp_path):
    for backend in ("numpy", "torch"):  # motion codes refined by both, as by default
        result = _apply(clips["long"], "--skeleton", clips["reference"], "--out", tmp_path / f"{backend}.npz",
                        "--backend", backend)
        assert result.exit_code == 0, result.output
    assert read_track(tmp_path / "numpy.npz").equals(read_track(tmp_path / "torch.npz"), atol=PX)


def test_a_folder_of_clips_gives_one_output_each_as_retargeted_alone(clips, tmp_path):
    out = tmp_path / "moved"
    result = _apply(clips["walk"].parent, "--skeleton", clips["reference"], "--out", out)
    assert result.exit_code == 0, result.output
    said = " ".join(result.output.split())  # rich wraps long lines
    assert f"wrote 4 clips to {out} (431 frames, npz" in said
    assert sorted(p.name for p in out.iterdir()) == ["long.npz", "mid.npz", "short.npz", "walk.npz"]
    for name in ("walk", "long", "short"):
        alone = tmp_path / f"{name}_alone.npz"
        assert _apply(clips[name], "--skeleton", clips["reference"], "--out", alone).exit_code == 0
        assert read_track(out / f"{name}.npz").equals(read_track(alone), atol=PX)


def test_several_inputs_in_another_format_and_overwriting(clips, tmp_path):
    out = tmp_path / "moved"
    args = [clips["walk"], clips["mid"], "--skeleton", clips["reference"], "--out", out, "--to", "csv"]
    assert _apply(*args).exit_code == 0
    assert sorted(p.name for p in out.iterdir()) == ["mid.csv", "walk.csv"]
    before = (out / "walk.csv").read_bytes()
    assert "--out" in _one_error_line(_apply(*args)) and (out / "walk.csv").read_bytes() == before
    assert _apply(*args, "--overwrite").exit_code == 0


def test_one_bad_clip_stops_the_run_before_any_output(clips, tmp_path):
    (clips["walk"].parent / "zz_broken.npz").write_bytes(b"not an npz")
    out = tmp_path / "moved"
    line = _one_error_line(_apply(clips["walk"].parent, "--skeleton", clips["reference"], "--out", out))
    assert "zz_broken.npz" in line
    assert not out.exists() or not any(out.iterdir())


def test_a_clip_too_short_is_named(clips, tmp_path):
    write_track(walking_figure(6), clips["walk"].parent / "tiny.npz")
    line = _one_error_line(_apply(clips["walk"].parent, "--skeleton", clips["reference"], "--out", tmp_path / "o"))
    assert "tiny.npz: 6 frames" in line and not (tmp_path / "o").exists()


@pytest.mark.parametrize("case, expected", [
    ("clash", "would both write"),
    ("preview", "--preview draws one result"),
    ("out is a file", "is a file"),
    ("out has a suffix", "give one without a suffix"),
    ("--to with one input", "--to sets the format"),
    ("empty folder", "no pose files"),
    ("named twice", "named twice"),
    ("bad backend", "unknown backend 'onnx'"),
])  # fmt: skip
def test_batch_usage_errors_are_one_line(clips, tmp_path, case, expected):
    ref, walk, folder = clips["reference"], clips["walk"], clips["walk"].parent
    (tmp_path / "empty").mkdir()
    (tmp_path / "a_file").write_text("x")
    argv = {
        "clash": [walk, write_track(walking_figure(30), tmp_path / "walk.csv"), "--out", tmp_path / "o"],
        "preview": [folder, "--out", tmp_path / "o", "--preview", tmp_path / "p.mp4"],
        "out is a file": [folder, "--out", tmp_path / "a_file"],
        "out has a suffix": [folder, "--out", tmp_path / "o.npz"],
        "--to with one input": [walk, "--out", tmp_path / "o.npz", "--to", "csv"],
        "empty folder": [tmp_path / "empty", "--out", tmp_path / "o"],
        "named twice": [walk, folder, "--out", tmp_path / "o"],
        "bad backend": [walk, "--out", tmp_path / "o.npz", "--backend", "onnx"],
    }[case]
    assert expected in _one_error_line(_apply(*argv, "--skeleton", ref))
    assert not (tmp_path / "o").exists() and not (tmp_path / "o.npz").exists()
