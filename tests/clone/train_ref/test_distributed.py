"""`clone train-ref` under torchrun with 2 CPU processes (gloo): the steps of one process, resumable either way.

A model started by one process is continued by ``torchrun --nproc-per-node 2`` and finished by one process
again; after each part it matches the model one process trains straight through. Tolerance: the float32 sums
of 2 processes (gradient all-reduce, convolutions over 1 sample instead of 2) differ in rounding from one
process's, and Adam turns that rounding on entries with near-zero gradients into visible steps, so the weights
are compared by the norm of their difference relative to the norm of the update (< 1e-2) and by the median
entry (< 1e-6); see tests/retarget/training/test_distributed.py for the gradient-level check.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import torch
from typer.testing import CliRunner

from clone.cli.main import app
from clone.model.networks import build_generator
from clone.model.reference import load_reference_model, preview_path
from clone.train_ref import TrainConfig
from tests.clone.train_ref.helpers import one_line_error, train_args
from tests.retarget.training.test_distributed import free_port

ROOT = Path(__file__).resolve().parents[3]


def _train(poses: Path, frames: Path, out: Path, steps: int, *extra: str) -> None:
    result = CliRunner().invoke(app, train_args(poses, frames, out, "--batch-size", "2", *extra, steps=steps))
    assert result.exit_code == 0, result.output


def _torchrun(args: list[str]) -> subprocess.CompletedProcess:
    env = {**os.environ, "OMP_NUM_THREADS": "1", "PYTHONPATH": str(ROOT)}
    command = [sys.executable, "-m", "torch.distributed.run", "--nproc-per-node", "2", "--master-addr",
               "127.0.0.1", "--master-port", str(free_port()), "-m", "clone", *args]
    return subprocess.run(command, check=False, cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)


def _assert_same_run(a: Path, b: Path) -> None:
    """Generators ``a`` and ``b`` trained from the same initial weights, up to float32 rounding (see the top)."""
    wa, wb = load_reference_model(a).generator_state, load_reference_model(b).generator_state
    torch.manual_seed(0)  # the run's seed: the fresh generator both started from
    start = build_generator("unet", TrainConfig(size=32).generator_config()).state_dict()
    flat_a, flat_b, flat_0 = (torch.cat([w[k].flatten().float() for k in wa]) for w in (wa, wb, start))
    assert (flat_a - flat_b).norm() < 1e-2 * (flat_b - flat_0).norm()
    assert (flat_a - flat_b).abs().median() < 1e-6


def test_two_processes_continue_a_model_and_one_finishes_it(reference, tmp_path):
    poses, frames = reference
    shared = tmp_path / "shared" / "ref.pt"
    _train(poses, frames, shared, 2)  # started by one process
    run = _torchrun(train_args(poses, frames, shared, "--resume", steps=4))
    assert run.returncode == 0, run.stdout + run.stderr
    assert run.stderr.count("trained 2 steps (total 4)") == 1  # rank 0 alone reports
    assert sorted(p.name for p in shared.parent.iterdir()) == sorted([shared.name, preview_path(shared).name])
    assert load_reference_model(shared).training["config"]["batch_size"] == 2  # the global batch

    straight = tmp_path / "straight" / "ref.pt"
    _train(poses, frames, straight, 4)
    _assert_same_run(shared, straight)
    shutil.copy(straight, straight.with_name("at4.pt"))
    _train(poses, frames, straight, 6, "--resume")
    _train(poses, frames, shared, 6, "--resume")  # a model 2 processes wrote, finished by one
    _assert_same_run(shared, straight)


def test_a_batch_smaller_than_the_processes_is_one_line_error(reference, tmp_path, monkeypatch):
    from retarget.training import distributed

    poses, frames = reference
    out = tmp_path / "ref.pt"
    monkeypatch.setattr(distributed, "current", lambda: distributed.World(0, 2))  # as rank 0 of 2 sees it
    error = one_line_error(CliRunner().invoke(app, train_args(poses, frames, out, "--batch-size", "1", steps=1)))
    assert error.startswith("error: --batch-size: a batch of 1 cannot be split over 2 processes")
    assert not out.exists()


def test_torchrun_with_the_default_batch_trains_one_sample_per_process(reference, tmp_path):
    poses, frames = reference
    out = tmp_path / "ref.pt"
    run = _torchrun(train_args(poses, frames, out, steps=1))  # no --batch-size
    assert run.returncode == 0, run.stdout + run.stderr
    assert load_reference_model(out).training["config"]["batch_size"] == 2
