"""The training loop (:func:`fit`): epochs, time budget, one checkpoint rewritten atomically, exact resume."""

from __future__ import annotations

import copy
import dataclasses
import logging
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch

from pose_io.errors import InputError
from pose_io.track import PoseTrack
from retarget import distributed
from retarget.checkpoint import RetargetWeights, load_checkpoint, save_checkpoint
from retarget.model import RetargetNet, variant_config
from retarget.training.average import WeightAverage
from retarget.training.config import DEFAULT_CONFIG, TrainConfig
from retarget.training.data import (
    CrossSamples,
    WorldSplit,
    _loader,
    _validation_set,
    body_scales,
    character_heights,
    mean_pose_height,
    real_windows,
    split_statistics,
)
from retarget.training.step import TrainLoss, character_proportions, evaluate, train_step

log = logging.getLogger(__name__)

CPU = torch.device("cpu")
DEFAULT_EPOCHS = 300  # the authors' schedule, used when neither epochs nor minutes are given


@dataclass(frozen=True)
class TrainProgress:
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


ProgressFn = Callable[[TrainProgress], None]


@dataclass(frozen=True)
class TrainSummary:
    """What a training run did.

    Attributes:
        checkpoint: the checkpoint file.
        epochs: completed epochs (in total, over all resumed runs).
        steps: optimisation steps (in total).
        stopped: "epochs" (all done) or "time" (budget used up).
        history: one dict per completed epoch (train and validation loss means, seconds).
        best_epoch: the epoch (from 1) whose weights ``best`` holds; None without ``best`` or when no epoch of
            this call beat the run's earlier ones.
        averaged_epochs: epochs this call added to the weight average ``average`` (0 without it).
    """

    checkpoint: Path
    epochs: int
    steps: int
    stopped: str
    history: list[dict[str, float]]
    best_epoch: int | None = None
    averaged_epochs: int = 0


def retargeting_error(record: dict[str, float], config: TrainConfig) -> float | None:
    """An epoch's validation retargeting error: the cross reconstruction loss (the reconstruction loss when the
    objective has none) plus the root-path loss, unweighted, when it is trained. None without validation.

    The root path is what moves most from epoch to epoch; on the validation split's eval cases it follows
    ``clone retarget eval``'s with-root error (see the model card).
    """
    loss = config.loss
    pose = record.get("val_cross") if loss.cross else record.get("val_rec")
    if pose is None:
        return None
    if loss.trajectory_weight > 0 and "val_trajectory" in record:
        pose += record["val_trajectory"] / loss.trajectory_weight
    return float(pose)


def fit(
    train_split: WorldSplit,
    val_split: WorldSplit | None,
    out: str | Path,
    config: TrainConfig = DEFAULT_CONFIG,
    device: torch.device = CPU,
    real_tracks: Sequence[PoseTrack] = (),
    epochs: int | None = None,
    minutes: float | None = None,
    resume: bool = False,
    num_workers: int = 0,
    progress: ProgressFn | None = None,
    init: RetargetWeights | None = None,
    amp: bool | None = None,
    best: str | Path | None = None,
    average: str | Path | None = None,
    average_from: int | None = None,
) -> TrainSummary:
    """Train (or continue training) a retargeting network and write its checkpoint.

    In a process group (``torchrun``, see :mod:`retarget.distributed`) every process runs this function:
    ``config.batch_size`` is the global batch, of which each process trains its part; the learning rate is
    that of one process. Rank 0 reports progress, validates and writes ``out``.

    Args:
        train_split: training split of the motion world.
        val_split: validation split (None: no validation).
        out: checkpoint file; must not exist unless ``resume``.
        config: training settings.
        device: where to train (the command line resolves ``--device``; one GPU per process).
        real_tracks: unlabelled real tracks (self-reconstruction only).
        epochs: total epochs to reach; None = until ``minutes`` run out, or 300 when both are None.
        minutes: wall-clock budget of this call.
        resume: continue the run stored in ``out`` (written by any number of processes).
        num_workers: data-loader worker processes (per process).
        progress: called after every step and every epoch, on rank 0 only (the library draws no bar).
        init: weights to start from (ours or the authors'; their statistics are kept, since the
            weights are tied to them); ignored with ``resume``.
        amp: bfloat16 autocast on CUDA (None: where the GPU supports it); ignored on the CPU.
        best: also write the weights (no training state) of every epoch whose :func:`retargeting_error` on
            validation is the lowest of the run so far (resumed runs included) to this file.
        average: also write the mean of the weights at the end of every epoch from ``average_from`` on
            (:class:`WeightAverage`, kept in ``out`` for resuming) to this file, rewritten after every epoch.
            Once a run averages, its later epochs join the mean even in calls without ``average``.
        average_from: the first epoch (from 1, over resumed runs) in the mean (None: the run's, else 1).

    Returns:
        A :class:`TrainSummary` (the same on every process).

    Raises:
        InputError: ``out`` exists without ``resume``, holds a run with other settings, or the batch is
            smaller than the number of processes.
    """
    out = Path(out)
    for extra, option in ((best, "best"), (average, "average")):
        if extra is not None and Path(extra).resolve() == out.resolve():
            raise InputError(f"{extra}: the {option} weights would replace the checkpoint; choose another file")
    if best is not None and average is not None and Path(best).resolve() == Path(average).resolve():
        raise InputError(f"{best}: the best and the averaged weights need two files")
    dev = torch.device(device)
    world = distributed.current()
    target_epochs = epochs if epochs is not None else (DEFAULT_EPOCHS if minutes is None else math.inf)
    deadline = time.monotonic() + 60.0 * minutes if minutes is not None else math.inf
    started = time.monotonic()
    try:
        part = distributed.shard(config.batch_size, world)
    except ValueError as exc:
        raise InputError(str(exc)) from None

    if resume:
        state = _resume_state(out, config)
        model, stats, training = state["model"], state["stats"], state["training"]
        preprocess = state["preprocess"]
        init_from = training.get("init")
        scales = body_scales(train_split, config, preprocess.body_height)
    else:
        _require_new(out)
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
        training = None
    model.to(dev)
    proportions = character_proportions(train_split).to(dev) if config.loss.skeleton_proportion_weight > 0 else None
    step_loss = distributed.wrap(TrainLoss(model, stats, config, proportions), dev)  # DDP with several processes
    dtype = distributed.amp_dtype(dev, amp)
    optimizer = torch.optim.Adam(model.parameters(), lr=config.lr, amsgrad=config.amsgrad)
    scheduler = torch.optim.lr_scheduler.ExponentialLR(optimizer, config.lr_decay)
    generator = torch.Generator().manual_seed(config.seed)
    real_rng = np.random.default_rng([config.seed, 104729])
    if training is not None:
        optimizer.load_state_dict(training["optimizer"])
        scheduler.load_state_dict(training["scheduler"])
        torch.set_rng_state(training["torch_rng"])  # rank 0's; other ranks re-seed every step
        generator.set_state(training["augment_rng"])
        real_rng.bit_generator.state = training["real_rng"]
    done = training or {}
    epoch: int = done.get("epoch", 0)
    # Once a run averages, every later epoch joins the mean, written out or not (a call without ``average``).
    stored = done.get("average")
    averager = None
    if average is not None or stored is not None:
        first = average_from if average_from is not None else stored["first"] if stored is not None else 1
        if stored is None and epoch >= first:
            raise InputError(f"the weight average starts at epoch {first}, but this run has done {epoch} "
                             "epochs without one; start it later")
        averager = WeightAverage(first, model, stored)
    step_in_epoch: int = done.get("step", 0)
    global_step: int = done.get("global_step", 0)
    elapsed_before: float = done.get("elapsed_s", 0.0)
    history: list[dict[str, float]] = list(done.get("history", []))

    size = config.samples_per_epoch
    dataset = CrossSamples(
        train_split, config.window, config.variant, size, config.seed, scales, config.cameras, preprocess.body_height,
        config.frontal_share,
    )
    steps_per_epoch = max(1, size // config.batch_size)
    val = None
    if val_split is not None and world.is_main:
        val = _validation_set(val_split, config, body_scales(val_split, config, preprocess.body_height))
    real = torch.from_numpy(real_windows(real_tracks, config.window, preprocess)) if real_tracks else None

    def save() -> None:
        # Nothing in it depends on the number of processes (see retarget.distributed).
        if world.is_main:
            save_checkpoint(out, model, stats, preprocess, training={
                "config": config.to_dict(), "init": init_from, "epoch": epoch, "step": step_in_epoch,
                "global_step": global_step, "optimizer": optimizer.state_dict(), "scheduler": scheduler.state_dict(),
                "torch_rng": torch.get_rng_state(), "augment_rng": generator.get_state(),
                "real_rng": real_rng.bit_generator.state,
                "elapsed_s": elapsed_before + time.monotonic() - started, "history": history,
                **({"average": averager.state()} if averager is not None else {}),
            })
        distributed.barrier()

    def report(update: TrainProgress) -> None:
        if progress is not None and world.is_main:
            progress(update)

    stopped = "epochs"
    best_epoch = None
    scores = [retargeting_error(r, config) for r in history]
    lowest = min((v for v in scores if v is not None and math.isfinite(v)), default=math.inf)
    averaged_before = averager.count if averager is not None else 0
    while epoch < target_epochs:
        dataset.epoch = epoch
        sums: dict[str, float] = {}
        counted = 0
        loader = _loader(dataset, step_in_epoch, steps_per_epoch, config.batch_size, num_workers, part,
                         pin=dev.type == "cuda")
        out_of_time = False
        for batch in loader:
            if world.rank > 0:  # rank 0 continues the stored generator, as a single process does
                torch.manual_seed(distributed.rank_seed(config.seed, world.rank, global_step))
            batch = {k: v.to(dev, non_blocking=True) for k, v in batch.items()}
            real_batch = None
            if real is not None and len(real):
                pick = real_rng.choice(len(real), min(config.real_batch_size, len(real)), replace=False)
                real_batch = real[torch.from_numpy(pick)].to(dev)
            losses = train_step(step_loss, optimizer, batch, stats, config, generator, real_batch, part=part,
                                total=config.batch_size, dtype=dtype)
            late = time.monotonic() > deadline
            losses, (late,) = distributed.reduce_logs(losses, part.stop - part.start, [late])
            for k, v in losses.items():
                sums[k] = sums.get(k, 0.0) + v
            counted += 1
            step_in_epoch += 1
            global_step += 1
            report(TrainProgress(epoch + 1, step_in_epoch, steps_per_epoch, global_step, losses))
            if late and step_in_epoch < steps_per_epoch:
                out_of_time = True
                break
        if out_of_time:
            save()
            stopped = "time"
            if world.is_main:
                log.info("time budget used up in epoch %d at step %d; checkpoint %s", epoch + 1, step_in_epoch, out)
            break
        epoch += 1
        step_in_epoch = 0
        scheduler.step()
        record = {"epoch": float(epoch), **{f"train_{k}": v / max(counted, 1) for k, v in sums.items()}}
        if val is not None:
            record.update({f"val_{k}": v for k, v in evaluate(model, *val, stats, config, dtype=dtype).items()})
        record["seconds"] = elapsed_before + time.monotonic() - started
        record = distributed.broadcast(record)  # rank 0 validated
        history.append(record)
        # The best and averaged weights go first: a run stopped before the checkpoint below redoes this epoch.
        if averager is not None and averager.update(epoch, model) and average is not None and world.is_main:
            save_checkpoint(average, averager.module(), stats, preprocess)
        score = retargeting_error(record, config)
        if best is not None and score is not None and math.isfinite(score) and score < lowest:
            lowest, best_epoch = score, epoch
            if world.is_main:
                save_checkpoint(best, model, stats, preprocess)
                log.info("epoch %d: lowest validation retargeting error so far (%.4f); weights in %s", epoch, score, best)
        save()
        report(TrainProgress(epoch, steps_per_epoch, steps_per_epoch, global_step, record))
        if world.is_main:
            log.info("epoch %d: %s", epoch, _format(record))
        if distributed.any_rank(time.monotonic() > deadline):
            stopped = "time" if epoch < target_epochs else "epochs"
            break
    return TrainSummary(out, epoch, global_step, stopped, history, best_epoch,
                        averager.count - averaged_before if average is not None else 0)


def _require_new(out: Path) -> None:
    if out.exists():
        raise InputError(f"{out}: already exists; pass --resume to continue that run, or choose another --out")


def _resume_state(out: Path, config: TrainConfig) -> dict[str, Any]:
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
    return {"model": loaded.model, "stats": loaded.stats, "training": loaded.training, "preprocess": loaded.preprocess}


def _format(losses: dict[str, float], prefix: str = "") -> str:
    keys = [k for k in losses if k.startswith(prefix) and k not in ("epoch", "seconds")]
    return " ".join(f"{k}={losses[k]:.4f}" for k in keys)
