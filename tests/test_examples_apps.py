"""The walkthroughs of latent interpolation and cartoons (examples/interpolate.sh, examples/cartoon.sh) run here
on tiny inputs built in tmp_path, so they cannot rot."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
FRAMES = 40


def run(args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ)
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"  # the venv's `clone`, `python`
    env["PYTHONPATH"] = os.pathsep.join([str(EXAMPLES.parent), env.get("PYTHONPATH", "")])  # `python -m clone...`
    result = subprocess.run(args, cwd=cwd, env=env, capture_output=True, text=True, timeout=600, check=False)
    assert result.returncode == 0, result.stdout[-2000:] + result.stderr[-2000:]
    return result


@pytest.fixture(scope="module")
def people(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Two OpenPose folders like the authors' examples (a tall and a small person), built here."""
    from pose_io.writers import write_track
    from tests.figures import tall_and_small

    folder = tmp_path_factory.mktemp("people")
    for name, track in tall_and_small(FRAMES).items():
        write_track(track, folder / f"{name}_man")
    return folder


def test_interpolate_example(people, tmp_path):
    out = tmp_path / "out"
    result = run(["bash", str(EXAMPLES / "interpolate.sh"), str(people / "tall_man"), str(people / "small_man"),
                  str(out)], tmp_path)
    assert (out / "motion_view.mp4").stat().st_size > 0
    assert np.load(out / "body_view.npz")["poses"].shape == (5, 5, FRAMES, 15, 2)
    assert "rows body, columns view, motion of A" in result.stdout


def test_cartoon_example(people, tmp_path):
    out = tmp_path / "out"
    run(["bash", str(EXAMPLES / "cartoon.sh"), str(people / "small_man"), str(out), "720x720"], tmp_path)
    for name in ("bighead", "longlegs"):
        assert (out / f"{name}.mp4").stat().st_size > 0
        report = json.loads((out / f"{name}.json").read_text())
        assert report["character"]["name"] == name and report["frames"] == FRAMES
    assert np.load(out / "longlegs_poses.npz")["joints"].shape == (FRAMES, 15, 2)
