"""Training in 2 CPU processes (gloo): the same steps as one process on the same global batch, resumable either way.

The processes are started once for the module with torch.multiprocessing and find each other through the
environment torchrun sets (RANK, WORLD_SIZE, LOCAL_RANK, MASTER_ADDR, MASTER_PORT), which
:func:`retarget.training.distributed.launched` reads. Dropout is off here: its masks are drawn per process (see
:mod:`retarget.training.distributed`); every other number of a step is the same as in one process.

Tolerances. What differs is the order of float32 sums (the gradient all-reduce, convolutions over 2 samples
instead of 4): the averaged gradient of a step equals one process's to ~1e-6 relative (GRAD_RTOL = 1e-5 is
asserted). AMSGrad divides each gradient entry by its own running magnitude, so on entries whose gradient is
~1e-6 of the largest that rounding noise becomes a visible step (up to lr); after a few AMSGrad steps the
parameters are therefore compared by the norm of their difference relative to the norm of the update
(< 1e-2 asserted, 4e-3 seen) and by the median entry (< 1e-6). The two processes agree with each other exactly.
"""

from __future__ import annotations

import dataclasses
import os
import socket
from pathlib import Path

import numpy as np
import pytest
import torch
import torch.multiprocessing as mp

from pose_io import PoseTrack
from retarget.network import model
from retarget.network.checkpoint import load_checkpoint
from retarget.training import distributed
from retarget.training.config import TrainConfig
from retarget.training.data import CrossSamples, real_windows, split_statistics
from retarget.training.loop import fit
from retarget.training.step import TrainLoss, train_step
from tests.retarget.training.fake_split import TINY, FakeSplit

EVEN = TINY  # a global batch of 4: 2 samples per process, 2 steps per epoch
UNEVEN = dataclasses.replace(TINY, batch_size=3, samples_per_epoch=6)  # 1 + 2 samples per step
GRAD_RTOL = 1e-5


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def no_dropout() -> None:
    model.VARIANTS["full"] = dataclasses.replace(model.VARIANTS["full"], dropout=0.0)


def real_track() -> PoseTrack:
    t = np.arange(72, dtype=np.float32)[:, None, None]
    rng = np.random.default_rng(0)
    joints = rng.normal(320, 60, (1, 25, 2)).astype(np.float32) + 4 * np.sin(t / 6.0)  # [72, 25, 2]
    return PoseTrack(joints, np.full(joints.shape[:2], 0.9, np.float32), 30.0, (640, 480), "body25")


def sgd_step(part: slice | None = None) -> tuple[dict[str, torch.Tensor], dict[str, float]]:
    """Minus the gradient of one step (SGD, lr 1) of a fresh network on 4 samples and 4 real windows, or of
    ``part`` of them in a process group; and the step's loss terms."""
    split = FakeSplit()
    stats = split_statistics(split, 64, 32, 0)
    samples = CrossSamples(split, 64, "full", 4, 0)
    items = [samples.sample(0, i) for i in range(4)][part or slice(None)]
    batch = {"windows": torch.from_numpy(np.stack([it["windows"] for it in items])),
             "ids": torch.from_numpy(np.stack([it["ids"] for it in items]))}
    real = torch.from_numpy(real_windows([real_track()], 64, EVEN.preprocess))[:4]
    torch.manual_seed(0)
    net = model.RetargetNet(model.variant_config("full"))
    before = {k: v.clone() for k, v in net.state_dict().items()}
    loss = distributed.wrap(TrainLoss(net, stats, EVEN), torch.device("cpu"))
    logs = train_step(loss, torch.optim.SGD(net.parameters(), lr=1.0), batch, stats, EVEN,
                      torch.Generator().manual_seed(0), real, part=part, total=4)
    return {k: v - net.state_dict()[k] for k, v in before.items()}, logs


def _worker(rank: int, port: int, tmp: Path) -> None:
    os.environ.update(RANK=str(rank), WORLD_SIZE="2", LOCAL_RANK=str(rank), LOCAL_WORLD_SIZE="2",
                      MASTER_ADDR="127.0.0.1", MASTER_PORT=str(port))
    torch.set_num_threads(1)
    no_dropout()
    seen: list = []
    with distributed.launched(torch.device("cpu")) as device:
        world = distributed.current()
        assert (world.rank, world.size, world.local_rank, device.type) == (rank, 2, rank, "cpu")
        grad, logs = sgd_step(distributed.shard(4, world))
        even = fit(FakeSplit(), FakeSplit(seed=1), tmp / "even2.pt", EVEN, device, real_tracks=[real_track()],
                   epochs=1, progress=seen.append)
        params = {"even": _params(even.checkpoint) if rank == 0 else None}
        # Rank 0 wrote the checkpoint; every process holds the same weights.
        uneven = fit(FakeSplit(), None, tmp / "uneven2.pt", UNEVEN, device, epochs=1, minutes=0.0)
        assert uneven.stopped == "time" and uneven.steps == 1
        # Resume a run a single process started.
        resumed = fit(FakeSplit(), None, tmp / "started1.pt", UNEVEN, device, epochs=1, resume=True)
        assert resumed.steps == 2
        mine = {"history": even.history, "progress": len(seen), "grad": grad, "logs": logs}
    torch.save({**params, **mine}, tmp / f"rank{rank}.pt")


def _params(path: Path) -> dict[str, torch.Tensor]:
    return load_checkpoint(path).model.state_dict()


def _assert_same_run(a: dict[str, torch.Tensor], b: dict[str, torch.Tensor]) -> None:
    """Weights ``a`` and ``b`` trained from the same initial weights, up to float32 rounding (see the top)."""
    assert a.keys() == b.keys()
    torch.manual_seed(0)
    start = model.RetargetNet(model.variant_config("full")).state_dict()
    flat_a, flat_b, flat_0 = (torch.cat([s[k].flatten() for k in a]) for s in (a, b, start))
    assert (flat_a - flat_b).norm() < 1e-2 * (flat_b - flat_0).norm()
    assert (flat_a - flat_b).abs().median() < 1e-6


@pytest.fixture(scope="module")
def two_process_runs(tmp_path_factory):
    """The folder of the 2-process runs of _worker (started once for the module); dropout off meanwhile."""
    tmp = tmp_path_factory.mktemp("ddp")
    threads = torch.get_num_threads()
    with pytest.MonkeyPatch.context() as patch:
        patch.setitem(model.VARIANTS, "full", dataclasses.replace(model.VARIANTS["full"], dropout=0.0))
        torch.set_num_threads(1)
        first = fit(FakeSplit(), None, tmp / "started1.pt", UNEVEN, epochs=1, minutes=0.0)
        assert first.steps == 1
        mp.spawn(_worker, args=(free_port(), tmp), nprocs=2, join=True)
        yield tmp
    torch.set_num_threads(threads)


def _ranks(tmp: Path) -> list[dict]:
    return [torch.load(tmp / f"rank{r}.pt", weights_only=False) for r in (0, 1)]


def test_the_averaged_gradient_is_that_of_the_global_batch(two_process_runs):
    ranks = _ranks(two_process_runs)
    grad, logs = sgd_step()  # dropout is off while the fixture is in use
    for key, g in grad.items():
        for rank in ranks:
            assert (rank["grad"][key] - g).norm() <= GRAD_RTOL * g.norm(), key
        torch.testing.assert_close(ranks[0]["grad"][key], ranks[1]["grad"][key], rtol=0, atol=0)
    # Each process logs the means of its 2 samples; their mean is the batch's (the real term: all of it).
    for key, value in logs.items():
        assert (ranks[0]["logs"][key] + ranks[1]["logs"][key]) / 2 == pytest.approx(value, rel=1e-5), key


def test_two_processes_take_the_steps_of_one(two_process_runs):
    tmp = two_process_runs
    ranks = _ranks(tmp)
    assert ranks[0]["progress"] == 3 and ranks[1]["progress"] == 0  # 2 steps + 1 epoch, rank 0 only
    assert ranks[0]["history"] == ranks[1]["history"]
    single = fit(FakeSplit(), FakeSplit(seed=1), tmp / "even1.pt", EVEN, real_tracks=[real_track()], epochs=1)
    _assert_same_run(_params(tmp / "even2.pt"), _params(single.checkpoint))
    for key, value in _params(tmp / "even2.pt").items():  # rank 0 wrote them; rank 1 holds the same
        torch.testing.assert_close(ranks[0]["even"][key], value, rtol=0, atol=0)
    two, one = ranks[0]["history"][-1], single.history[-1]
    assert two.keys() == one.keys() and "train_real" in two and "val_total" in two
    for key in ("train_total", "train_real", "val_total"):  # losses are means over the global batch
        assert two[key] == pytest.approx(one[key], rel=1e-4)


def test_a_two_process_checkpoint_resumes_in_one_process_and_back(two_process_runs):
    tmp = two_process_runs
    whole = fit(FakeSplit(), None, tmp / "whole1.pt", UNEVEN, epochs=2)
    # Stopped by 2 processes after step 1 of 2 (uneven parts: 1 + 2 samples); finished by one.
    rest = fit(FakeSplit(), None, tmp / "uneven2.pt", UNEVEN, epochs=2, resume=True)
    assert rest.steps == 4 and rest.epochs == 2
    _assert_same_run(_params(tmp / "uneven2.pt"), _params(whole.checkpoint))
    # Started by one process, its first epoch finished by 2 (in the fixture), then by one again.
    fit(FakeSplit(), None, tmp / "started1.pt", UNEVEN, epochs=2, resume=True)
    _assert_same_run(_params(tmp / "started1.pt"), _params(whole.checkpoint))


def test_the_batch_is_split_into_contiguous_parts():
    worlds = [distributed.World(r, 3) for r in range(3)]
    assert [distributed.shard(8, w) for w in worlds] == [slice(0, 2), slice(2, 5), slice(5, 8)]
    weights = [distributed.shard_weight(distributed.shard(8, w), 8, w) for w in worlds]
    assert sum(weights) == pytest.approx(3.0)  # DDP averages: the weighted means average to the global mean
    assert distributed.shard(4, distributed.World()) == slice(0, 4)
    with pytest.raises(ValueError, match="cannot be split over 3 processes"):
        distributed.shard(2, worlds[0])


def test_the_torchrun_environment_is_read():
    env = {"RANK": "3", "WORLD_SIZE": "4", "LOCAL_RANK": "1", "LOCAL_WORLD_SIZE": "2"}
    assert distributed.from_environment(env) == distributed.World(3, 4, 1, 2)
    assert distributed.from_environment({}) is None
    with pytest.raises(ValueError, match="do not fit"):
        distributed.from_environment({"RANK": "4", "WORLD_SIZE": "4"})
    assert distributed.current() == distributed.World()  # no process group in this process
    assert distributed.cpu_threads(distributed.World(0, 4, 0, 2), free=2) == 1
    assert distributed.rank_seed(0, 1, 5) != distributed.rank_seed(0, 2, 5) != distributed.rank_seed(0, 2, 6)


def test_a_batch_smaller_than_the_world_is_refused(tmp_path, monkeypatch):
    from pose_io.errors import InputError

    monkeypatch.setattr(distributed, "current", lambda: distributed.World(0, 2))
    with pytest.raises(InputError, match="a batch of 1 cannot be split over 2 processes"):
        fit(FakeSplit(), None, tmp_path / "r.pt", TrainConfig(batch_size=1), epochs=1)
    assert not (tmp_path / "r.pt").exists()
