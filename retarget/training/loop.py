"""The training loop (:func:`fit`): epochs, time budget, one checkpoint rewritten atomically, exact resume, the
best epoch and the weight average. A run's state and where it starts: :mod:`retarget.training.state`."""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

import torch

from pose_io.errors import InputError
from pose_io.track import PoseTrack
from retarget.network.checkpoint import RetargetWeights, save_checkpoint
from retarget.training import distributed
from retarget.training.config import DEFAULT_CONFIG, TrainConfig
from retarget.training.data import CrossSamples, WorldSplit, batch_loader, body_scales, validation_set
from retarget.training.state import EpochProgress, ProgressFn, TrainingRun, begin_run, start_run
from retarget.training.step import evaluate, train_step

log = logging.getLogger(__name__)

CPU = torch.device("cpu")
DEFAULT_EPOCHS = 300  # the authors' schedule, used when neither epochs nor minutes are given


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

    In a process group (``torchrun``, see :mod:`retarget.training.distributed`) every process runs this function:
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
    _check_extra_files(out, best, average)
    dev = torch.device(device)
    world = distributed.current()
    target_epochs = epochs if epochs is not None else (DEFAULT_EPOCHS if minutes is None else math.inf)
    deadline = time.monotonic() + 60.0 * minutes if minutes is not None else math.inf
    started = time.monotonic()
    try:
        part = distributed.shard(config.batch_size, world)
    except ValueError as exc:
        raise InputError(str(exc)) from None
    begin = begin_run(train_split, out, config, resume, init)
    run = start_run(begin, train_split, out, config, device=dev, amp=amp, real_tracks=real_tracks, average=average,
                    average_from=average_from, progress=progress, world=world, part=part, deadline=deadline,
                    started=started)  # fmt: skip
    dataset = CrossSamples(
        train_split, config.window, config.variant, config.samples_per_epoch, config.seed, begin.scales,
        config.cameras, run.preprocess.body_height, config.frontal_share, config.turn_share, config.turn_range,
        config.splice_share, config.bend_deg, config.source_balance,
    )
    val = None
    if val_split is not None and world.is_main:
        val = validation_set(val_split, config, body_scales(val_split, config, run.preprocess.body_height))

    stopped = "epochs"
    best_epoch = None
    scores = [retargeting_error(r, config) for r in run.history]
    lowest = min((v for v in scores if v is not None and math.isfinite(v)), default=math.inf)
    averaged_before = run.averager.count if run.averager is not None else 0
    while run.epoch < target_epochs:
        dataset.epoch = run.epoch
        loader = batch_loader(dataset, run.step_in_epoch, run.steps_per_epoch, config.batch_size, num_workers, part,
                              pin=dev.type == "cuda")  # fmt: skip
        sums, counted, out_of_time = _train_epoch(run, loader)
        if out_of_time:
            run.save()
            stopped = "time"
            if world.is_main:
                log.info("time budget used up in epoch %d at step %d; checkpoint %s", run.epoch + 1,
                         run.step_in_epoch, out)  # fmt: skip
            break
        record = _close_epoch(run, sums, counted, val)
        # The best and averaged weights go first: a run stopped before the checkpoint below redoes this epoch.
        if run.averager is not None and run.averager.update(run.epoch, run.model) and average is not None \
                and world.is_main:
            save_checkpoint(average, run.averager.module(), run.stats, run.preprocess)
        score = retargeting_error(record, config)
        if best is not None and score is not None and math.isfinite(score) and score < lowest:
            lowest, best_epoch = score, run.epoch
            if world.is_main:
                save_checkpoint(best, run.model, run.stats, run.preprocess)
                log.info("epoch %d: lowest validation retargeting error so far (%.4f); weights in %s", run.epoch,
                         score, best)  # fmt: skip
        run.save()
        run.report(EpochProgress(run.epoch, run.steps_per_epoch, run.steps_per_epoch, run.global_step, record))
        if world.is_main:
            log.info("epoch %d: %s", run.epoch, _format(record))
        if distributed.any_rank(time.monotonic() > deadline):
            stopped = "time" if run.epoch < target_epochs else "epochs"
            break
    return TrainSummary(out, run.epoch, run.global_step, stopped, run.history, best_epoch,
                        run.averager.count - averaged_before if average is not None else 0)


def _check_extra_files(out: Path, best: str | Path | None, average: str | Path | None) -> None:
    """The best and averaged weights each need a file of their own, neither of them the checkpoint."""
    for extra, option in ((best, "best"), (average, "average")):
        if extra is not None and Path(extra).resolve() == out.resolve():
            raise InputError(f"{extra}: the {option} weights would replace the checkpoint; choose another file")
    if best is not None and average is not None and Path(best).resolve() == Path(average).resolve():
        raise InputError(f"{best}: the best and the averaged weights need two files")


def _train_epoch(run: TrainingRun, loader: Iterable[dict[str, torch.Tensor]]) -> tuple[dict[str, float], int, bool]:
    """The steps of the current epoch from where it stands, until it ends or the time is up; the sums of the
    steps' losses, how many steps they hold, and whether the time ran out before the epoch's last step."""
    config, world = run.config, run.world
    sums: dict[str, float] = {}
    counted = 0
    for batch in loader:
        if world.rank > 0:  # rank 0 continues the stored generator, as a single process does
            torch.manual_seed(distributed.rank_seed(config.seed, world.rank, run.global_step))
        batch = {k: v.to(run.device, non_blocking=True) for k, v in batch.items()}
        real_batch = None
        if run.real is not None and len(run.real):
            pick = run.real_rng.choice(len(run.real), min(config.real_batch_size, len(run.real)), replace=False)
            real_batch = run.real[torch.from_numpy(pick)].to(run.device)
        losses = train_step(run.step_loss, run.optimizer, batch, run.stats, config, run.generator, real_batch,
                            part=run.part, total=config.batch_size, dtype=run.dtype)  # fmt: skip
        late = time.monotonic() > run.deadline
        losses, (late,) = distributed.reduce_logs(losses, run.part.stop - run.part.start, [late])
        for k, v in losses.items():
            sums[k] = sums.get(k, 0.0) + v
        counted += 1
        run.step_in_epoch += 1
        run.global_step += 1
        run.report(EpochProgress(run.epoch + 1, run.step_in_epoch, run.steps_per_epoch, run.global_step, losses))
        if late and run.step_in_epoch < run.steps_per_epoch:
            return sums, counted, True
    return sums, counted, False


def _close_epoch(run: TrainingRun, sums: dict[str, float], counted: int,
                 val: tuple[torch.Tensor, torch.Tensor] | None) -> dict[str, float]:
    """Count the epoch done, step the schedule, validate (rank 0) and add the epoch's record to the history."""
    run.epoch += 1
    run.step_in_epoch = 0
    run.scheduler.step()
    record = {"epoch": float(run.epoch), **{f"train_{k}": v / max(counted, 1) for k, v in sums.items()}}
    if val is not None:
        record.update({f"val_{k}": v for k, v in evaluate(run.model, *val, run.stats, run.config,
                                                           dtype=run.dtype).items()})  # fmt: skip
    record["seconds"] = run.total_seconds()
    record = distributed.broadcast(record)  # rank 0 validated
    run.history.append(record)
    return record


def _format(losses: dict[str, float], prefix: str = "") -> str:
    keys = [k for k in losses if k.startswith(prefix) and k not in ("epoch", "seconds")]
    return " ".join(f"{k}={losses[k]:.4f}" for k in keys)
