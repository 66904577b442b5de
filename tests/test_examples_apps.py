"""The walkthroughs of latent interpolation and cartoons (examples/interpolate.sh, examples/cartoon.sh) run here
on tiny inputs built in tmp_path, so they cannot rot."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tests.examples_support import EXAMPLES, write_people
from tests.examples_support import run_example as run

FRAMES = 40


@pytest.fixture(scope="module")
def people(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Two OpenPose folders like the authors' examples (a tall and a small person), built here."""
    return write_people(tmp_path_factory.mktemp("people"), FRAMES)


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
