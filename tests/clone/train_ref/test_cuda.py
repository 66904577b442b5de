"""`clone train-ref --device cuda`: bfloat16 autocast by default (--no-amp: float32), a model the CPU loads;
2 GPUs train in 2 processes under torchrun (NCCL). Marked ``cuda``: deselected by default (``-m cuda`` runs
them) and skipped without a GPU."""

from __future__ import annotations

import pytest
import torch
from typer.testing import CliRunner

from clone.cli.main import app
from clone.model.reference import load_reference_model, preview_path
from clone.train_ref import TrainConfig, train_reference
from tests.clone.train_ref.helpers import train_args
from tests.clone.train_ref.test_distributed import _torchrun

pytestmark = [
    pytest.mark.cuda,
    pytest.mark.skipif(not torch.cuda.is_available(), reason="needs a CUDA GPU"),
]


def _cuda_args(args: list[str]) -> list[str]:
    i = args.index("--device")
    return args[:i + 1] + ["cuda"] + args[i + 2:]


@pytest.mark.parametrize("amp", ["--amp", "--no-amp"])
def test_train_ref_on_cuda_writes_a_model_the_cpu_drives(reference, tmp_path, amp):
    poses, frames = reference
    out = tmp_path / "ref.pt"
    result = CliRunner().invoke(app, _cuda_args(train_args(poses, frames, out, "--batch-size", "2", amp)))
    assert result.exit_code == 0, result.output
    model = load_reference_model(out)
    assert model.training["device"].startswith("cuda")
    assert all(v.dtype == torch.float32 for v in model.generator_state.values())
    assert preview_path(out).is_file()
    net = model.build_generator()  # on the CPU
    assert torch.isfinite(net(torch.zeros(1, 6, 32, 32), model.plate_tensor())).all()
    resumed = CliRunner().invoke(app, _cuda_args(train_args(poses, frames, out, "--resume", amp, steps=5)))
    assert resumed.exit_code == 0, resumed.output
    assert load_reference_model(out).training["steps"] == 5


def test_amp_default_is_bfloat16_autocast(reference, tmp_path, monkeypatch):
    from clone.train_ref import trainer as trainer_module

    seen = []
    original = trainer_module.Trainer.__init__

    def spy(self, *args, **kwargs):
        original(self, *args, **kwargs)
        seen.append(self.dtype)

    monkeypatch.setattr(trainer_module.Trainer, "__init__", spy)
    poses, frames = reference
    train_reference(poses, frames, tmp_path / "ref.pt", config=TrainConfig(size=32), steps=1,
                    device=torch.device("cuda"))
    assert seen == [torch.bfloat16 if torch.cuda.is_bf16_supported() else None]


@pytest.mark.skipif(torch.cuda.device_count() < 2, reason="needs 2 CUDA GPUs")
def test_two_gpus_under_torchrun(reference, tmp_path):
    poses, frames = reference
    out = tmp_path / "ref.pt"
    run = _torchrun(_cuda_args(train_args(poses, frames, out, "--batch-size", "2")))
    assert run.returncode == 0, run.stdout + run.stderr
    assert run.stderr.count("trained 3 steps") == 1
    assert load_reference_model(out).training["steps"] == 3
