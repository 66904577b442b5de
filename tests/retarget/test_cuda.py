"""Training the retargeting network on CUDA: bfloat16 autocast by default, float32 with amp=False, pinned
loaders; 2 GPUs train in 2 processes (NCCL). Marked ``cuda``: deselected by default (``-m cuda`` runs them) and
skipped without a GPU."""

from __future__ import annotations

import dataclasses

import pytest
import torch
import torch.multiprocessing as mp

from retarget.api import load_retargeter
from retarget.network import model
from retarget.network.checkpoint import load_checkpoint
from retarget.training import distributed
from retarget.training.loop import fit
from tests.retarget.training.fake_split import TINY, FakeSplit
from tests.retarget.training.test_distributed import free_port

pytestmark = [
    pytest.mark.cuda,
    pytest.mark.skipif(not torch.cuda.is_available(), reason="needs a CUDA GPU"),
]
CUDA = torch.device("cuda")


def _flat(path) -> torch.Tensor:
    return torch.cat([v.flatten() for v in load_checkpoint(path).model.state_dict().values()])


def test_amp_is_bfloat16_on_cuda_only():
    expected = torch.bfloat16 if torch.cuda.is_bf16_supported() else None
    assert distributed.amp_dtype(CUDA) == expected
    assert distributed.amp_dtype(CUDA, amp=False) is None
    assert distributed.amp_dtype(torch.device("cpu"), amp=True) is None


def test_fit_on_cuda_writes_a_float32_checkpoint_the_cpu_loads(tmp_path, walking_track):
    summary = fit(FakeSplit(), FakeSplit(seed=1), tmp_path / "r.pt", TINY, CUDA, epochs=2, num_workers=1)
    assert summary.steps == 4
    record = summary.history[-1]
    assert all(torch.isfinite(torch.tensor(v)) for v in record.values())
    loaded = load_checkpoint(tmp_path / "r.pt")
    assert all(v.dtype == torch.float32 and v.device.type == "cpu" for v in loaded.model.state_dict().values())
    retargeter = load_retargeter(tmp_path / "r.pt", device="cpu")
    assert len(retargeter.retarget(walking_track, retargeter.reference_codes(walking_track))) == len(walking_track)
    # Resumed on CUDA from its own checkpoint.
    assert fit(FakeSplit(), None, tmp_path / "r.pt", TINY, CUDA, epochs=3, resume=True).epochs == 3


def test_float32_on_cuda_takes_the_steps_of_the_cpu(tmp_path, monkeypatch):
    monkeypatch.setitem(model.VARIANTS, "full", dataclasses.replace(model.VARIANTS["full"], dropout=0.0))
    monkeypatch.setattr(torch.backends.cudnn, "allow_tf32", False)  # cuDNN's default rounds to 10 bits
    fit(FakeSplit(), None, tmp_path / "gpu.pt", TINY, CUDA, epochs=1, amp=False)
    fit(FakeSplit(), None, tmp_path / "cpu.pt", TINY, torch.device("cpu"), epochs=1)
    torch.manual_seed(0)
    start = torch.cat([v.flatten() for v in model.RetargetNet(model.variant_config("full")).state_dict().values()])
    gpu, cpu = _flat(tmp_path / "gpu.pt"), _flat(tmp_path / "cpu.pt")
    # float32 rounding differs; Adam makes it visible on near-zero gradients (see test_distributed.py).
    assert (gpu - cpu).norm() < 5e-2 * (cpu - start).norm()


def _worker(rank: int, port: int, tmp) -> None:
    import os

    os.environ.update(RANK=str(rank), WORLD_SIZE="2", LOCAL_RANK=str(rank), LOCAL_WORLD_SIZE="2",
                      MASTER_ADDR="127.0.0.1", MASTER_PORT=str(port))
    with distributed.launched(CUDA) as device:
        assert device == torch.device("cuda", rank)
        assert torch.distributed.get_backend() == "nccl"
        fit(FakeSplit(), None, tmp / "ddp.pt", TINY, device, epochs=1)


@pytest.mark.skipif(torch.cuda.device_count() < 2, reason="needs 2 CUDA GPUs")
def test_two_gpus_train_in_two_processes(tmp_path):
    mp.spawn(_worker, args=(free_port(), tmp_path), nprocs=2, join=True)
    loaded = load_checkpoint(tmp_path / "ddp.pt")
    assert loaded.training["global_step"] == 2
    assert fit(FakeSplit(), None, tmp_path / "ddp.pt", TINY, CUDA, epochs=2, resume=True).steps == 4
