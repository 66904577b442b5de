"""A training run's state: where it starts (a new network, given weights, or the run stored in the checkpoint),
what its steps and epochs share (:class:`TrainingRun`), its checkpoint with the resume state, and its progress
reports. The loop itself is :func:`retarget.training.loop.fit`.
"""

from __future__ import annotations

import copy
import dataclasses
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
import torch

from pose_io.errors import InputError
from pose_io.track import PoseTrack
from retarget.network.checkpoint import RetargetWeights, load_checkpoint, save_checkpoint
from retarget.network.model import RetargetNet, variant_config
from retarget.network.preprocess import NormStats, PreprocessConfig
from retarget.training import distributed
from retarget.training.average import WeightAverage
from retarget.training.config import TrainConfig
from retarget.training.data import (
    WorldSplit,
    body_scales,
    character_heights,
    mean_pose_height,
    real_windows,
    split_statistics,
)
from retarget.training.step import TrainLoss, character_proportions


@dataclass(frozen=True)
class EpochProgress:
    """Where a training run stands, passed to a progress callback after every step and every epoch.

    Attributes:
        epoch: the current epoch, counted from 1.
        step: steps done in this epoch.
        steps_per_epoch: steps an epoch has.
        global_step: steps done in total (over resumed runs too).
        losses: the last step's loss terms, or at the end of an epoch (``step == steps_per_epoch``) the
            epoch's record (train means, ``val_*`` validation losses).
    """

    epoch: int
    step: int
    steps_per_epoch: int
    global_step: int
    losses: dict[str, float]


ProgressFn = Callable[[EpochProgress], None]


class RunStart(NamedTuple):
    """What a run starts from: the network, its statistics and canvas settings, the characters' body scales,
    where the weights came from, and the stored training state (None for a new run)."""

    model: RetargetNet
    stats: NormStats
    preprocess: PreprocessConfig
    scales: np.ndarray | None
    init_from: str | None
    training: dict[str, Any] | None


def begin_run(
    train_split: WorldSplit, out: Path, config: TrainConfig, resume: bool, init: RetargetWeights | None
) -> RunStart:
    """The stored run (``resume``), the given weights (``init``) or a new seeded network, with what goes with it.

    Args:
        train_split: the training split (its characters' heights set a new run's body height and scales).
        out: the checkpoint file: read with ``resume``, else it must not exist.
        config: the run's settings; a resumed run must have been trained with the same.
        resume: continue the run stored in ``out``.
        init: weights to start a new run from (their statistics are kept), or None.

    Raises:
        InputError: ``out`` exists without ``resume``, holds no run or one with other settings, or ``init`` is
            another variant.
    """
    if resume:
        stored = _stored_run(out, config)
        scales = body_scales(train_split, config, stored.preprocess.body_height)
        return RunStart(stored.model, stored.stats, stored.preprocess, scales, stored.training.get("init"),
                        stored.training)
    require_new(out)
    torch.manual_seed(config.seed)
    if init is not None:
        if init.variant != config.variant:
            raise InputError(f"{init.path}: a {init.variant} network; this run trains a {config.variant} one")
        model, stats, init_from = copy.deepcopy(init.model), init.stats, str(init.path)
        target = mean_pose_height(stats)
    else:
        model, stats, init_from = RetargetNet(variant_config(config.variant)), None, None
        target = float(np.median(character_heights(train_split, config.window, 8, config.seed)))
    target = round(target, 3)  # as stored, so that a resumed run computes the same scales
    scales = body_scales(train_split, config, target)
    preprocess = config.preprocess
    if scales is not None:
        preprocess = dataclasses.replace(preprocess, body_height=target)
    if stats is None:
        stats = split_statistics(train_split, config.window, config.stats_windows, config.seed, scales)
    return RunStart(model, stats, preprocess, scales, init_from, None)


@dataclass
class TrainingRun:
    """A run in progress: what its steps, epochs, checkpoints and progress reports share."""

    out: Path
    config: TrainConfig
    model: RetargetNet
    stats: NormStats
    preprocess: PreprocessConfig
    init_from: str | None
    step_loss: torch.nn.Module  # TrainLoss, wrapped in DistributedDataParallel with several processes
    optimizer: torch.optim.Optimizer
    scheduler: torch.optim.lr_scheduler.LRScheduler
    generator: torch.Generator  # draws the augmentation
    real_rng: np.random.Generator  # picks each step's real windows
    real: torch.Tensor | None  # [N, window, 15, 2] real windows in the canvas, or None
    averager: WeightAverage | None
    dtype: torch.dtype | None  # autocast
    device: torch.device
    part: slice  # this process's samples of each global batch
    steps_per_epoch: int
    deadline: float  # time.monotonic() when the budget ends
    started: float  # time.monotonic() when this call began
    progress: ProgressFn | None
    world: distributed.World
    epoch: int = 0  # completed epochs, over resumed runs
    step_in_epoch: int = 0
    global_step: int = 0
    seconds_before: float = 0.0  # training time of earlier calls
    history: list[dict[str, float]] = field(default_factory=list)

    def elapsed(self) -> float:
        """Seconds since this call began."""
        return time.monotonic() - self.started

    def total_seconds(self) -> float:
        """Seconds of training over all calls of this run."""
        return self.seconds_before + self.elapsed()

    def save(self) -> None:
        """Rank 0 rewrites the checkpoint (nothing in it depends on the number of processes); all wait for it."""
        if self.world.is_main:
            save_checkpoint(self.out, self.model, self.stats, self.preprocess, training={
                "config": self.config.to_dict(), "init": self.init_from, "epoch": self.epoch,
                "step": self.step_in_epoch, "global_step": self.global_step,
                "optimizer": self.optimizer.state_dict(), "scheduler": self.scheduler.state_dict(),
                "torch_rng": torch.get_rng_state(), "augment_rng": self.generator.get_state(),
                "real_rng": self.real_rng.bit_generator.state, "elapsed_s": self.total_seconds(), "history": self.history,
                **({"average": self.averager.state()} if self.averager is not None else {}),
            })
        distributed.barrier()

    def report(self, update: EpochProgress) -> None:
        """Hand ``update`` to the progress callback, on rank 0 only."""
        if self.progress is not None and self.world.is_main:
            self.progress(update)


def start_run(
    begin: RunStart, train_split: WorldSplit, out: Path, config: TrainConfig, *, device: torch.device,
    amp: bool | None, real_tracks: Sequence[PoseTrack], average: str | Path | None, average_from: int | None,
    progress: ProgressFn | None, world: distributed.World, part: slice, deadline: float, started: float,
) -> TrainingRun:
    """The optimiser, schedule, random generators and weight average of a run, restored when it resumes.

    Args:
        begin: what the run starts from (:func:`begin_run`).
        train_split: the training split (its characters' proportions feed the proportion term).
        out: the checkpoint file.
        config: the run's settings.
        device: where to train.
        amp: bfloat16 autocast on CUDA (None: where supported).
        real_tracks: unlabelled real tracks for the self-reconstruction term.
        average, average_from: see :func:`retarget.training.loop.fit`.
        progress: the progress callback (rank 0 only).
        world: this process's place in the process group.
        part: this process's samples of each global batch.
        deadline: ``time.monotonic()`` when the time budget ends.
        started: ``time.monotonic()`` when this call began.
    """
    model = begin.model.to(device)
    proportions = character_proportions(train_split).to(device) if config.loss.skeleton_proportion_weight > 0 else None
    step_loss = distributed.wrap(TrainLoss(model, begin.stats, config, proportions), device)
    dtype = distributed.amp_dtype(device, amp)
    optimizer = torch.optim.Adam(model.parameters(), lr=config.lr, amsgrad=config.amsgrad)
    scheduler = torch.optim.lr_scheduler.ExponentialLR(optimizer, config.lr_decay)
    generator = torch.Generator().manual_seed(config.seed)
    real_rng = np.random.default_rng([config.seed, 104729])
    training = begin.training
    if training is not None:
        optimizer.load_state_dict(training["optimizer"])
        scheduler.load_state_dict(training["scheduler"])
        torch.set_rng_state(training["torch_rng"])  # rank 0's; other ranks re-seed every step
        generator.set_state(training["augment_rng"])
        real_rng.bit_generator.state = training["real_rng"]
    done = training or {}
    real = torch.from_numpy(real_windows(real_tracks, config.window, begin.preprocess)) if real_tracks else None
    return TrainingRun(
        out=out, config=config, model=model, stats=begin.stats, preprocess=begin.preprocess,
        init_from=begin.init_from, step_loss=step_loss, optimizer=optimizer, scheduler=scheduler, generator=generator,
        real_rng=real_rng, real=real, averager=_weight_average(model, done, average, average_from), dtype=dtype,
        device=device, part=part, steps_per_epoch=max(1, config.samples_per_epoch // config.batch_size),
        deadline=deadline, started=started, progress=progress, world=world, epoch=done.get("epoch", 0),
        step_in_epoch=done.get("step", 0), global_step=done.get("global_step", 0),
        seconds_before=done.get("elapsed_s", 0.0), history=list(done.get("history", [])),
    )


def _weight_average(
    model: RetargetNet, done: dict[str, Any], average: str | Path | None, average_from: int | None
) -> WeightAverage | None:
    """The run's weight average: asked for (``average``) or stored (once a run averages, every later epoch
    joins the mean, written out or not); None otherwise."""
    stored = done.get("average")
    if average is None and stored is None:
        return None
    first = average_from if average_from is not None else stored["first"] if stored is not None else 1
    epoch = done.get("epoch", 0)
    if stored is None and epoch >= first:
        raise InputError(f"the weight average starts at epoch {first}, but this run has done {epoch} "
                         "epochs without one; start it later")
    return WeightAverage(first, model, stored)


def require_new(out: Path) -> None:
    """InputError when ``out`` exists: a new run never replaces a checkpoint."""
    if out.exists():
        raise InputError(f"{out}: already exists; pass --resume to continue that run, or choose another --out")


def _stored_run(out: Path, config: TrainConfig) -> RetargetWeights:
    """The run stored in ``out`` (model, statistics, canvas settings, training state); InputError when there is
    none or it was trained with settings other than ``config``."""
    if not out.exists():
        raise InputError(f"{out}: nothing to resume (no such checkpoint)")
    loaded = load_checkpoint(out)
    if loaded.training is None:
        raise InputError(f"{out}: holds no training state to resume (only weights)")
    stored = TrainConfig.from_dict(loaded.training["config"]).to_dict()  # settings added since: their defaults
    mine = config.to_dict()
    changed = sorted(k for k in set(stored) | set(mine) if stored.get(k) != mine.get(k))
    if changed:
        raise InputError(f"{out}: was trained with other settings ({', '.join(changed)}); resume with the same ones")
    return loaded
