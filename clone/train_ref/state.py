"""A `clone train-ref` run's state: where it starts (a new model, or the one at ``--out`` resumed), what its steps
share (:class:`TrainingRun`: trainer, random generator, clock, checkpoint, progress reports). The loop itself is
:func:`clone.train_ref.loop.train_reference`; the retargeting trainer keeps the same convention
(:mod:`retarget.training.state`).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import torch

from clone.model.reference import ReferenceModel
from clone.train_ref.checkpoint import ReferenceInfo, load_resumable, restore, resume_config, save_checkpoint
from clone.train_ref.config import TrainConfig
from clone.train_ref.trainer import Trainer
from pose_io.errors import InputError
from retarget.training import distributed


@dataclass
class StepProgress:
    """Where a reference model's training stands, passed to the progress callback after every step (and every
    frame read); the retargeting trainer's counterpart, per epoch, is :class:`retarget.training.state.EpochProgress`.

    While ``phase`` is ``"reading"``, ``step`` counts frames read out of ``total``.
    """

    phase: str
    step: int
    total: int | None
    elapsed: float
    limit_s: float | None
    losses: dict[str, float]


ProgressFn = Callable[[StepProgress], None]


@dataclass
class TrainingRun:
    """A run in progress: what steps, checkpoints and progress reports share."""

    out: Path
    trainer: Trainer
    reference: ReferenceInfo
    config: TrainConfig
    rng: torch.Generator  # CPU: picks samples and draws the augmentation
    seconds_before: float  # training time of earlier runs of this model
    progress: ProgressFn | None
    started: float = 0.0  # time.perf_counter() when stepping began
    world: distributed.World = field(default_factory=distributed.World)
    part: slice | None = None  # this process's samples of each global batch (None: all)

    def elapsed(self) -> float:
        """Seconds since this call began stepping (what --minutes counts)."""
        return time.perf_counter() - self.started

    def total_seconds(self) -> float:
        """Seconds of training over all calls of this model."""
        return self.seconds_before + self.elapsed()

    def save(self) -> None:
        """Rank 0 writes the model file (nothing in it depends on the number of processes); all wait for it."""
        if self.world.is_main:
            save_checkpoint(self.out, self.trainer, self.reference, self.config, self.rng, self.total_seconds())
        distributed.barrier()

    def report(self, progress: StepProgress) -> None:
        """Hand ``progress`` to the progress callback, on rank 0 only."""
        if self.progress is not None and self.world.is_main:
            self.progress(progress)


def check_options(resume: bool, overwrite: bool, steps: int | None, minutes: float | None) -> None:
    """InputError for options that exclude each other or are out of range."""
    if resume and overwrite:
        raise InputError("--resume and --overwrite exclude each other")
    if steps is not None and steps < 1:
        raise InputError(f"--steps must be >= 1, got {steps}")
    if minutes is not None and not minutes > 0:
        raise InputError(f"--minutes must be positive, got {minutes}")


def previous_and_config(
    out: Path, given: TrainConfig | None, resume: bool, overwrite: bool
) -> tuple[ReferenceModel | None, TrainConfig]:
    """The model being resumed (None for a new one) and the run's config."""
    if resume:
        previous = load_resumable(out)
        return previous, resume_config(previous, given, out)
    if out.exists() and not overwrite:
        raise InputError(f"{out}: already exists; pass --resume to continue it, --overwrite to replace "
                         "it, or choose another --out")
    return None, given or TrainConfig()


def start_run(
    out: Path, reference: ReferenceInfo, config: TrainConfig, *, device: torch.device,
    previous: ReferenceModel | None, progress: ProgressFn | None, world: distributed.World, part: slice | None,
    dtype: torch.dtype | None = None, init: tuple[ReferenceModel, dict[str, Any] | None] | None = None,
) -> TrainingRun:
    """Seeded networks and random generator, restored from ``previous`` when resuming.

    Args:
        out: the model file.
        reference: what the model stores about the reference.
        config: the run's settings.
        device: where to train.
        previous: the model being resumed, or None.
        progress: the progress callback (rank 0 only).
        world: this process's place in the process group.
        part: this process's samples of each global batch (None: all).
        dtype: autocast dtype, or None.
        init: a new run's starting networks (:func:`clone.train_ref.checkpoint.load_init`): the model whose
            generator it copies, and the discriminator state to copy, or None.
    """
    torch.manual_seed(config.seed)
    start = previous if previous is not None else (init[0] if init is not None else None)
    generator = start.build_generator(device).train() if start is not None else None
    # the face pass too, when the run trains one and the model it starts from has one
    face_pass = start.face_pass_net(device) if start is not None and config.face_pass else None
    trainer = Trainer(config, device, generator, dtype, face_pass=face_pass.train() if face_pass else None)
    if previous is None and init is not None and init[1] is not None:
        trainer.d.load_state_dict(init[1]["state_dict"])
    rng = torch.Generator().manual_seed(config.seed)
    seconds_before = 0.0
    if previous is not None:
        restore(trainer, rng, previous, out)
        seconds_before = float(previous.training.get("seconds", 0.0))
    return TrainingRun(out=out, trainer=trainer, reference=reference, config=config, rng=rng,
                       seconds_before=seconds_before, progress=progress, started=time.perf_counter(), world=world,
                       part=part)
