"""Training on several processes: what both trainers share to run under ``torchrun``.

``torchrun --nproc-per-node N`` (and multi-node ``torchrun --rdzv-endpoint``) starts N copies of a command with
``RANK``, ``WORLD_SIZE``, ``LOCAL_RANK`` (and the rendezvous address) in their environment.
:func:`launched` detects them, starts the process group (gloo on the CPU, NCCL on CUDA, where rank r uses
``cuda:LOCAL_RANK``) and ends it again; inside it the trainers ask :func:`current` where they stand.

The convention of both trainers (``retarget.training.loop.fit`` and ``clone.train_ref.loop.train_reference``):

* the batch size is the GLOBAL batch: step s uses the same samples, augmented with the same random numbers, as
  a single process would; rank r computes the losses of its contiguous part (:func:`shard`) and
  DistributedDataParallel averages the gradients. The learning rate is unchanged, so N processes take the
  same steps as one, up to the order of floating-point sums (about 1e-6 relative in float32);
* every random source that decides WHAT is learned (sample choice, augmentation) is one CPU generator in the
  same state on every rank: each rank draws the numbers of the whole batch and keeps its part. Its state does
  not depend on the number of processes, so a checkpoint resumes under any world size;
* the global torch generator (dropout) is per rank: rank 0 continues the stored state, as a single process
  does; rank r > 0 is re-seeded before every step from (seed, rank, step) (:func:`rank_seed`);
* rank 0 alone reports progress and writes the checkpoint (atomically); the others wait at a barrier.
  Every rank reads the inputs and, on resume, the checkpoint: they must be on a filesystem all nodes see.

Nothing here runs at import time, and a single process (no ``torchrun``) never touches torch.distributed.
"""

from __future__ import annotations

import contextlib
import logging
import os
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from datetime import timedelta
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
import torch
from torch import nn

log = logging.getLogger(__name__)

T = TypeVar("T")


@dataclass(frozen=True)
class World:
    """Where this process stands among the processes of one training run.

    Attributes:
        rank: this process, 0 to ``size - 1``.
        size: number of processes (``WORLD_SIZE``).
        local_rank: this process among those of its machine (its GPU).
        local_size: processes on this machine.
    """

    rank: int = 0
    size: int = 1
    local_rank: int = 0
    local_size: int = 1

    @property
    def is_main(self) -> bool:
        """Rank 0: the one that reports and writes."""
        return self.rank == 0

    @property
    def distributed(self) -> bool:
        return self.size > 1


def from_environment(environ: Mapping[str, str] | None = None) -> World | None:
    """The world ``torchrun`` describes in the environment, or None when not started by it.

    Raises:
        ValueError: the variables are there but do not make sense.
    """
    env = os.environ if environ is None else environ
    if "RANK" not in env or "WORLD_SIZE" not in env:
        return None
    try:
        rank, size = int(env["RANK"]), int(env["WORLD_SIZE"])
        local_rank = int(env.get("LOCAL_RANK", rank))
        local_size = int(env.get("LOCAL_WORLD_SIZE", size))
    except ValueError:
        raise ValueError("RANK, WORLD_SIZE, LOCAL_RANK must be integers (as torchrun sets them)") from None
    if not 0 <= rank < size or not 0 <= local_rank < local_size:
        raise ValueError(f"RANK {rank} / WORLD_SIZE {size} (LOCAL_RANK {local_rank}) do not fit together")
    return World(rank, size, local_rank, local_size)


def _initialised() -> bool:
    return torch.distributed.is_available() and torch.distributed.is_initialized()


def current() -> World:
    """The world of the process group started by :func:`init` (or by the caller); one process otherwise."""
    if not _initialised():
        return World()
    dist = torch.distributed
    rank, size = dist.get_rank(), dist.get_world_size()
    env = from_environment()
    if env is not None and (env.rank, env.size) == (rank, size):
        return env
    return World(rank, size, rank, size)


def rank_device(world: World, device: torch.device) -> torch.device:
    """The device of this rank: ``cuda:LOCAL_RANK`` when training on CUDA, else ``device``."""
    if device.type != "cuda":
        return device
    if device.index is not None and device.index != world.local_rank:
        log.warning("rank %d uses cuda:%d (its LOCAL_RANK), not %s", world.rank, world.local_rank, device)
    return torch.device("cuda", world.local_rank)


def init(world: World, device: torch.device, timeout_s: float = 1800.0) -> torch.device:
    """Start the process group of ``world`` (gloo on the CPU, NCCL on CUDA); returns this rank's device.

    The rendezvous address comes from the environment (``MASTER_ADDR``/``MASTER_PORT``, set by torchrun).
    """
    dev = rank_device(world, device)
    if dev.type == "cuda":
        torch.cuda.set_device(dev)
        torch.distributed.init_process_group("nccl", rank=world.rank, world_size=world.size,
                                             timeout=timedelta(seconds=timeout_s), device_id=dev)
    else:
        torch.distributed.init_process_group("gloo", rank=world.rank, world_size=world.size,
                                             timeout=timedelta(seconds=timeout_s))
    log.info("rank %d of %d on %s", world.rank, world.size, dev)
    return dev


def destroy() -> None:
    """End the process group, if one was started."""
    if _initialised():
        torch.distributed.destroy_process_group()


@contextlib.contextmanager
def launched(device: torch.device) -> Iterator[torch.device]:
    """Run the body in the process group ``torchrun`` asks for (if any); yields this rank's device.

    Without ``torchrun`` (or with a group the caller started already) it yields ``device`` unchanged.
    """
    world = from_environment()
    if world is None or _initialised():
        yield rank_device(world, device) if world is not None else device
        return
    dev = init(world, device)
    try:
        yield dev
    finally:
        destroy()


def cpu_threads(world: World, free: int) -> int:
    """Threads per process when ``world.local_size`` processes share ``free`` cores (at least 1)."""
    return max(1, free // max(1, world.local_size))


def shard(total: int, world: World) -> slice:
    """The contiguous part of ``total`` items (the global batch) this rank computes.

    Rank r takes ``[r * total // N, (r + 1) * total // N)``: equal parts when N divides ``total``.

    Raises:
        ValueError: fewer items than processes.
    """
    if total < world.size:
        raise ValueError(f"a batch of {total} cannot be split over {world.size} processes; "
                         f"the batch size is the global batch, give at least {world.size}")
    return slice(world.rank * total // world.size, (world.rank + 1) * total // world.size)


def shard_weight(part: slice, total: int, world: World) -> float:
    """Factor of a rank's mean loss so that the average over ranks is the mean over the global batch.

    DistributedDataParallel averages gradients over ranks; a rank holding ``n`` of ``total`` samples weighs
    its mean by ``n * N / total`` (1.0 for equal parts).
    """
    return (part.stop - part.start) * world.size / total


def rank_seed(seed: int, rank: int, step: int) -> int:
    """Seed of rank ``rank``'s global torch generator before step ``step`` (ranks > 0; see the module doc)."""
    return int(np.random.SeedSequence([seed, rank, step, 0x0D15]).generate_state(1, np.uint64)[0]) >> 1


def wrap(module: nn.Module, device: torch.device) -> nn.Module:
    """``module`` in DistributedDataParallel when several processes train, else itself.

    Only the training step calls the wrapper; what one rank does alone (validation, previews) calls the plain
    module, which involves no collective.
    """
    if not current().distributed:
        return module
    from torch.nn.parallel import DistributedDataParallel

    ids = [device.index] if device.type == "cuda" else None
    return DistributedDataParallel(module, device_ids=ids)


def _device() -> torch.device:
    if torch.distributed.get_backend() == "nccl":
        return torch.device("cuda", torch.cuda.current_device())
    return torch.device("cpu")


def reduce_logs(
    logs: Mapping[str, float], weight: float, flags: Sequence[bool] = ()
) -> tuple[dict[str, float], list[bool]]:
    """Weighted mean over ranks of loss logs, and whether any rank raised each flag, in ONE all-reduce.

    Every rank must pass the same keys in the same order and as many flags.

    Args:
        logs: this rank's loss values.
        weight: their weight (the rank's number of samples).
        flags: this rank's flags (out of time, ...).

    Returns:
        ``(logs, flags)``; unchanged with one process.
    """
    if not current().distributed:
        return dict(logs), list(flags)
    values = [v * weight for v in logs.values()] + [weight] + [float(f) for f in flags]
    vec = torch.tensor(values, dtype=torch.float64, device=_device())
    torch.distributed.all_reduce(vec)
    total = vec[len(logs)].item()
    means = {k: vec[i].item() / total for i, k in enumerate(logs)}
    return means, [vec[len(logs) + 1 + i].item() > 0 for i in range(len(flags))]


def any_rank(flag: bool) -> bool:
    """True on every rank when ``flag`` is true on one (e.g. a time budget, read on each rank's clock)."""
    if not current().distributed:
        return flag
    vec = torch.tensor([float(flag)], device=_device())
    torch.distributed.all_reduce(vec, op=torch.distributed.ReduceOp.MAX)
    return bool(vec.item() > 0)


def broadcast(obj: T) -> T:
    """Rank 0's ``obj`` on every rank (plain picklable data)."""
    if not current().distributed:
        return obj
    box = [obj]
    torch.distributed.broadcast_object_list(box, src=0)
    return box[0]


def barrier() -> None:
    """Wait until every rank is here (no-op for one process)."""
    if current().distributed:
        torch.distributed.barrier()


@contextlib.contextmanager
def main_first() -> Iterator[None]:
    """Local rank 0 runs the body first (e.g. building a cache); the other ranks run it after it finished."""
    world = current()
    if not world.distributed:
        yield
        return
    if world.local_rank != 0:
        torch.distributed.barrier()
    yield
    if world.local_rank == 0:
        torch.distributed.barrier()


# ---------------------------------------------------------------------------------------------------------
# Mixed precision (CUDA only)


def amp_dtype(device: torch.device, amp: bool | None = None, cpu: bool = False) -> torch.dtype | None:
    """bfloat16 autocast for ``device``, or None (full precision).

    Args:
        device: where the networks run.
        amp: True / False, or None for on wherever the GPU supports bfloat16 (the CPU then stays in float32).
        cpu: ``amp=True`` also applies on the CPU (where it has bfloat16 instructions, :func:`cpu_has_bf16`);
            without it the CPU always runs in float32.
    """
    if amp is False:
        return None
    if device.type == "cpu":
        # Opt-in only: on the generator it gave 1.6x the steps but less quality per minute (docs/cloning.md).
        if not (cpu and amp):
            return None
        if cpu_has_bf16():
            return torch.bfloat16
        log.warning("this CPU has no bfloat16 instructions; training in float32")
        return None
    if device.type != "cuda":
        return None
    if not torch.cuda.is_bf16_supported():
        if amp:
            log.warning("%s does not support bfloat16; training in float32", device)
        return None
    return torch.bfloat16


def cpu_has_bf16() -> bool:
    """Whether this CPU runs bfloat16 convolutions natively (AVX512-BF16 or AMX), not emulated.

    oneDNN emulates bfloat16 on plain AVX512, slower than float32, so its own answer is not enough: the CPU's
    flags must name the instructions too (Linux's /proc/cpuinfo; elsewhere oneDNN alone decides).
    """
    try:
        if not torch.ops.mkldnn._is_mkldnn_bf16_supported():
            return False
    except (AttributeError, RuntimeError):
        return False
    try:
        flags = Path("/proc/cpuinfo").read_text(errors="replace")
    except OSError:
        return True
    return "avx512_bf16" in flags or "amx_bf16" in flags


def autocast(device: torch.device, dtype: torch.dtype | None) -> contextlib.AbstractContextManager[Any]:
    """``torch.autocast`` to ``dtype`` on ``device``, or nothing when ``dtype`` is None."""
    if dtype is None:
        return contextlib.nullcontext()
    return torch.autocast(device.type, dtype=dtype)
