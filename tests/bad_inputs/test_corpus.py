"""Every case of the bad-input corpus ends as ONE ``error:`` line and exit code 2, touching nothing the user had.

In-process through typer's CliRunner (fast); the SIGTERM check runs `python -m clone` in a subprocess.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
import warnings
from pathlib import Path

import pytest
from typer.testing import CliRunner

from clone.cli.main import app
from tests.bad_inputs.cases import CASES, Case

REPO = Path(__file__).resolve().parents[2]


def snapshot(root: Path) -> dict[Path, bytes | None]:
    """Every file (its bytes) and folder (None) under ``root``."""
    return {p: (p.read_bytes() if p.is_file() else None) for p in sorted(root.rglob("*"))}


def check_one_error_line(exit_code: int, stderr: str, stdout: str) -> None:
    assert exit_code == 2, f"exit {exit_code}\nstdout: {stdout}\nstderr: {stderr}"
    assert "Traceback" not in stderr + stdout, stderr
    lines = [line for line in stderr.splitlines() if line.strip()]
    assert len(lines) == 1, f"expected one stderr line, got {len(lines)}:\n{stderr}"
    assert lines[0].startswith("error: ") and len(lines[0]) > len("error: "), lines[0]


def check_untouched(before: dict[Path, bytes | None], root: Path) -> None:
    after = snapshot(root)
    for path, content in before.items():
        assert path in after, f"{path} was removed"
        assert after[path] == content, f"{path} was changed"
    hidden = [p for p in after if p not in before and any(part.startswith(".") for part in p.relative_to(root).parts)]
    assert not hidden, f"hidden leftovers: {hidden}"


def run_case(case: Case, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)  # default outputs (ref_model.pt) land in the case's folder
    monkeypatch.setenv("OMP_NUM_THREADS", "1")
    monkeypatch.setenv("CLONE2D_WORLD_CACHE", str(tmp_path / "world-cache"))
    for build in case.build:
        build(tmp_path)
    before = snapshot(tmp_path)
    argv = [arg.replace("{t}", str(tmp_path)) for arg in case.argv]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = CliRunner().invoke(app, argv)
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception
    check_one_error_line(result.exit_code, result.stderr, result.stdout)
    ours = [w for w in caught if issubclass(w.category, RuntimeWarning)]
    assert not ours, f"numpy warnings on bad input: {[str(w.message) for w in ours]}"
    check_untouched(before, tmp_path)


def _param(case: Case):
    marks = [pytest.mark.xfail(strict=False, reason=case.xfail)] if case.xfail else []
    return pytest.param(case, id=case.id, marks=marks)


def test_the_corpus_is_big_enough():
    assert len(CASES) >= 250
    commands = {" ".join(c.argv[:2]) if c.argv[0] in ("pose", "retarget", "synth", "world", "search")
                else c.argv[0] for c in CASES}
    assert commands >= {"pose info", "pose show", "pose convert", "pose extract", "retarget apply",
                        "retarget train", "retarget eval", "retarget interpolate", "train-ref", "train-prior", "drive",
                        "report",
                        "demo", "synth render", "world build", "search index", "search query", "search eval",
                        "cartoon"}


@pytest.mark.parametrize("case", [_param(c) for c in CASES])
def test_bad_input(case: Case, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    run_case(case, tmp_path, monkeypatch)


def test_sigterm_during_drive_leaves_no_temp_file(tmp_path: Path) -> None:
    """SIGTERM mid-video: the atomic writer's temp file goes, no output appears, and the exit is 128 + 15."""
    from pose_io.writers import write_track
    from tests.clone.train_ref.helpers import figure_track, train_args, write_reference

    poses, frames = write_reference(tmp_path / "ref", figure_track(12))
    model = tmp_path / "ref.pt"
    env = {**os.environ, "OMP_NUM_THREADS": "1", "PYTHONPATH": str(REPO)}
    trained = CliRunner().invoke(app, train_args(poses, frames, model, steps=1))
    assert trained.exit_code == 0, trained.output
    driver = write_track(figure_track(20_000), tmp_path / "long.npz")
    out = tmp_path / "out.mp4"
    proc = subprocess.Popen(
        [sys.executable, "-m", "clone", "drive", str(driver), "--out", str(out), "--model", str(model),
         "--method", "none", "--device", "cpu", "--threads", "1"],
        cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    try:
        deadline = time.monotonic() + 120
        while not list(tmp_path.glob(".out.mp4.*")) and time.monotonic() < deadline and proc.poll() is None:
            time.sleep(0.05)
        assert proc.poll() is None, proc.communicate()
        assert list(tmp_path.glob(".out.mp4.*")), "the video never started"
        time.sleep(0.3)
        proc.send_signal(signal.SIGTERM)
        _, stderr = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 128 + signal.SIGTERM, stderr
    assert "Traceback" not in stderr, stderr
    assert not out.exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")], list(tmp_path.iterdir())
