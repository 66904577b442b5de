"""Code silhouettes and their plots."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from retarget.evaluate import EvalConfig, code_silhouettes, pca_2d, silhouette
from retarget.evaluate.codes import code_grid
from retarget.evaluate.run import network_method
from retarget.world import MotionWorld


def test_silhouette_known_value_separated_and_random() -> None:
    # 1-D points: cluster 0 = {0, 1}, cluster 1 = {10}. s(0) = (10 - 1) / 10, s(1) = (9 - 1) / 9, s(10) = 0.
    assert silhouette(np.array([[0.0], [1.0], [10.0]]), np.array([0, 0, 1])) == pytest.approx((0.9 + 8 / 9) / 3)
    rng = np.random.default_rng(0)
    labels = np.repeat(np.arange(3), 20)
    centres = np.array([[0.0, 0.0], [100.0, 0.0], [0.0, 100.0]])
    assert silhouette(centres[labels] + rng.normal(0, 1, (60, 2)), labels) > 0.95
    assert abs(silhouette(rng.normal(0, 1, (300, 8)), rng.integers(0, 3, 300))) < 0.05
    with pytest.raises(ValueError):
        silhouette(np.zeros((4, 2)), np.zeros(4))


def test_pca_finds_the_spread_directions() -> None:
    rng = np.random.default_rng(0)
    x = rng.normal(0, 0.01, (50, 6))
    x[:, 3] += np.linspace(-5, 5, 50)  # the largest spread
    x[:, 1] += rng.choice([-1.0, 1.0], 50)  # the second
    xy = pca_2d(x)
    assert abs(np.corrcoef(xy[:, 0], x[:, 3])[0, 1]) > 0.99
    assert abs(np.corrcoef(xy[:, 1], x[:, 1])[0, 1]) > 0.99


# Run in a fresh interpreter: whether pyplot was imported, and the backend, are process-wide.
_PLOT_SCRIPT = """
import sys
from pathlib import Path

import matplotlib
import numpy as np

from retarget.evaluate import plot_codes

rng = np.random.default_rng(0)
codes = {"motion": rng.normal(size=(12, 5)), "view": rng.normal(size=(12, 5))}
labels = {"motion": np.repeat(np.arange(3), 4), "view": np.tile(np.arange(4), 3)}
plot_codes(Path(sys.argv[1]), "tiny", codes, labels, {"motion": 0.5, "view": -0.1})
print("pyplot imported:", "matplotlib.pyplot" in sys.modules)
print("backend:", matplotlib.get_backend())
"""


def test_plotting_codes_leaves_matplotlib_alone(tmp_path: Path) -> None:
    path = tmp_path / "codes.png"
    env = {**os.environ, "MPLBACKEND": "svg", "OMP_NUM_THREADS": "1"}
    run = subprocess.run([sys.executable, "-c", _PLOT_SCRIPT, str(path)], env=env, capture_output=True,
                         text=True, timeout=300, check=False)  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert "pyplot imported: False" in run.stdout
    assert "backend: svg" in run.stdout
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_silhouettes_average_grids_that_keep_the_first(tiny_mocap: Path, cache: Path, tiny_weights: Path) -> None:
    split = MotionWorld.build(tiny_mocap, cache).split("test")
    net = network_method(tiny_weights, refine_steps=0)[1]
    one = EvalConfig(pairs=1, code_grids=1)
    first = code_grid(split, one, 0)
    again = code_grid(split, one, 1)
    assert np.array_equal(np.unique(first[:, 2]), np.unique(again[:, 2]))  # the same views
    assert not np.array_equal(first, again)  # other windows and characters
    scores, errors, codes, labels = code_silhouettes(net, split, one)
    assert scores == {k: pytest.approx(silhouette(codes[k], labels[k])) for k in codes}  # grid 0 alone
    assert errors == {k: 0.0 for k in codes}
    mean, se, codes3, _ = code_silhouettes(net, split, EvalConfig(pairs=1, code_grids=3))
    assert all(np.array_equal(codes3[k], codes[k]) for k in codes)  # the plotted grid is still grid 0
    assert all(se[k] > 0 for k in codes) and mean != scores
