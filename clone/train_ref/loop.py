"""The training loop of `clone train-ref`: one run from the reference's files to the model file.

A run reads the reference (:mod:`clone.train_ref.data`), builds or resumes the :class:`Trainer`, steps it on
augmented batches until the step or time budget is spent, writes previews (pose map | generated | real) and
checkpoints the model file with its training state (:mod:`clone.train_ref.checkpoint`). Progress goes to a
callback; the caller draws it. Ctrl-C ends the run early and still saves (in a single process).

Under ``torchrun`` every process runs :func:`train_reference` (see :mod:`retarget.training.distributed`): each reads
the whole reference, the batch size is the GLOBAL batch, of which process r trains its contiguous part, and the
run's generator (sample choice, augmentation) draws the numbers of the whole batch on every process, so a step
is one process's step and the stored state resumes under any number of processes. Rank 0 reports, writes
the previews and the model; the others wait for it. The periodic save and the time budget are decided on
rank 0's clock and shared, so that every process stops after the same step.
"""

from __future__ import annotations

import logging
import os
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import torch

from clone.model.canvas import choose_canvas, cut_frame, image_to_canvas
from clone.model.exemplar import GAP_SECONDS, LIMBS, choose_bank
from clone.model.reference import DETAIL_LAYOUT, LAYOUT, ReferenceModel, preview_path
from clone.train_ref.augment import (
    WHOLE_CANVAS_SHARE,
    crop,
    person_window,
    random_affines,
    warp_batch,
    warped_points,
)
from clone.train_ref.checkpoint import ReferenceInfo, load_init
from clone.train_ref.config import TrainConfig
from clone.train_ref.data import (
    ReferenceData,
    frame_store,
    maybe_scale_stats,
    read_reference,
    reference_codes,
    reference_plate,
    track_summary,
    usable_frames,
)
from clone.train_ref.preview import preview_grid, preview_rows, write_png
from clone.train_ref.state import (
    ProgressFn,
    StepProgress,
    TrainingRun,
    check_options,
    previous_and_config,
    start_run,
)
from pose_io.errors import InputError
from pose_io.track import PoseTrack
from retarget.runtime import ThreadGrowth
from retarget.training import distributed

if TYPE_CHECKING:
    from pose_io.video import Frames

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class TrainResult:
    """What a training run did."""

    model_path: Path
    preview_path: Path
    steps: int
    steps_this_run: int
    seconds: float
    frames: int
    usable_frames: int
    skipped_frames: int
    has_codes: bool
    interrupted: bool
    last_losses: dict[str, float]


def train_reference(
    poses_path: str | os.PathLike,
    frames_path: str | os.PathLike,
    out: str | os.PathLike = "ref_model.pt",
    *,
    config: TrainConfig | None = None,
    steps: int | None = None,
    minutes: float | None = None,
    device: torch.device | str = "cpu",
    resume: bool = False,
    overwrite: bool = False,
    align: str = "exact",
    weights: str | os.PathLike | None = None,
    progress: ProgressFn | None = None,
    amp: bool | None = None,
    grow_threads: bool = False,
    init: str | os.PathLike | None = None,
) -> TrainResult:
    """Train (or continue training) a reference model (in every process of a ``torchrun`` group, if any).

    Args:
        poses_path: the reference's poses (any format ``pose_io`` reads).
        frames_path: the reference's video or image folder, frame ``t`` matching pose ``t``.
        out: the model file to write (with its training state inside).
        config: settings of a new run (default ``TrainConfig()``). When resuming, the stored run's settings
            apply; of ``config`` only ``batch_size``, ``preview_every`` and ``save_every_s`` are taken, and
            a different ``size`` is an error. ``batch_size`` is the global batch over all processes.
        steps: stop when the model has been trained this many steps in total.
        minutes: stop after this many minutes of training in this run (reading the frames not counted).
        device: where to train (one GPU per process).
        resume: continue the model at ``out`` from the training state stored in it.
        overwrite: replace an existing model at ``out`` with a new one.
        align: ``exact`` or ``trim`` (see :func:`read_reference`).
        weights: retargeting weights for the reference codes (default: the shipped ones, if present).
        progress: called after every step (and every frame read), on rank 0 only.
        amp: bfloat16 autocast (None: on CUDA where the GPU supports it; on the CPU only when True, where it
            has bfloat16 instructions).
        grow_threads: on the CPU, in one process, raise torch's threads whenever more cores come free
            (:class:`retarget.runtime.ThreadGrowth`); `clone train-ref` without ``--threads`` sets it.
        init: a new run starts from the generator (and discriminator) of this model instead of random weights;
            it must have the same architecture (see :func:`clone.train_ref.checkpoint.load_init`).

    Returns:
        What was done.

    Raises:
        InputError: bad options, unreadable or mismatched inputs, an existing ``out`` without ``resume`` or
            ``overwrite``, ``resume`` of a model without training state, or a batch smaller than the number
            of processes.
    """
    out = Path(out)
    check_options(resume, overwrite, steps, minutes)
    previous, config = previous_and_config(out, config, resume, overwrite)
    if init is not None and resume:
        raise InputError("--init starts a new model; --resume continues one: pass only one of them")
    start = load_init(init, config) if init is not None else None
    if start is not None and config.init_lr is not None:  # stored with the model, so a resumed run keeps it
        config = replace(config, lr=config.init_lr)
    world = distributed.current()
    try:
        part = distributed.shard(config.batch_size, world)
    except ValueError as exc:
        raise InputError(f"--batch-size: {exc}") from None
    if steps is None and minutes is None:
        steps = config.steps
    detailed, frames, count = read_reference(poses_path, frames_path, align, layout=DETAIL_LAYOUT)
    track = detailed.to_layout(LAYOUT)
    usable = _usable(track, config.min_visible_joints, poses_path, count)
    reference = _reference_info(track, usable, config, previous, frames_path, weights)
    if config.pose_layout == DETAIL_LAYOUT:
        reference = replace(reference, details=detailed)
    device = torch.device(device)
    run = start_run(out, reference, config, device=device, previous=previous, progress=progress, world=world,
                    part=part, dtype=distributed.amp_dtype(device, amp, cpu=True), init=start)
    start_step = run.trainer.step_count

    # A run that fails (or is terminated) leaves no preview of a model it did not write.
    preview_before = preview_path(out).exists()
    try:
        # Training needs autograd whatever mode the caller left torch in.
        with torch.enable_grad(), frame_store(count, reference.canvas.size) as store:
            data = _read_frames(run, frames, count, usable, store)
            _add_plate(run, data, previous)
            _add_exemplars(run, data, previous, track.fps)
            rows = preview_rows(data.indices)
            run.started = time.perf_counter()  # --minutes counts training only
            limit_s = minutes * 60.0 if minutes is not None else None
            grow = ThreadGrowth() if grow_threads and device.type == "cpu" and world.size == 1 else None
            losses, interrupted = _train_steps(run, data, rows, steps, limit_s, grow)
            if world.is_main:
                write_png(preview_grid(run.trainer, data, rows), preview_path(out))
            run.save()
    except BaseException:
        if world.is_main and not preview_before and not out.exists():
            preview_path(out).unlink(missing_ok=True)
        raise

    return TrainResult(
        model_path=out, preview_path=preview_path(out), steps=run.trainer.step_count,
        steps_this_run=run.trainer.step_count - start_step, seconds=run.elapsed(), frames=count,
        usable_frames=int(usable.sum()), skipped_frames=int((~usable).sum()), has_codes=reference.codes is not None,
        interrupted=interrupted, last_losses=losses,
    )


def _usable(track: PoseTrack, min_visible: int, poses_path: str | os.PathLike, count: int) -> np.ndarray:
    """[T] bool frames trained on; an error when there are none, a warning when some are skipped."""
    usable = usable_frames(track, min_visible)
    if not usable.any():
        raise InputError(f"{poses_path}: no frame has a usable pose (>= {min_visible} of "
                         f"{len(track.joint_layout)} joints visible)")
    skipped = int((~usable).sum())
    if skipped:
        log.warning("%d of %d frames have no usable pose and are skipped", skipped, count)
    return usable


def _reference_info(
    track: PoseTrack, usable: np.ndarray, config: TrainConfig, previous: ReferenceModel | None,
    frames_path: str | os.PathLike, weights: str | os.PathLike | None,
) -> ReferenceInfo:
    """What the model stores about the reference: a resumed model keeps its canvas, codes and scale."""
    summary = track_summary(track, usable)
    if previous is not None:
        canvas = previous.canvas
        if canvas.image_size != track.image_size:
            raise InputError(f"{frames_path}: frames are {track.image_size[0]}x{track.image_size[1]}, "
                             f"the model was trained on {canvas.image_size[0]}x{canvas.image_size[1]}")
        return ReferenceInfo(canvas, previous.scale_stats, track, summary, previous.reference_codes,
                             previous.codes_weights, previous.codes_weights_path)
    canvas = choose_canvas(track.joints[usable], track.image_size, config.size, config.canvas_mode,
                           config.canvas_margin)
    codes, codes_weights, codes_path = reference_codes(track, weights)
    return ReferenceInfo(canvas, maybe_scale_stats(track), track, summary, codes, codes_weights, codes_path)


def _read_frames(run: TrainingRun, frames: Frames, count: int, usable: np.ndarray, store: np.ndarray) -> ReferenceData:
    """Cut the first ``count`` frames to the canvas into ``store``; the training data over them."""
    canvas = run.reference.canvas
    for i, frame in enumerate(frames):
        if i >= count:
            break
        store[i] = cut_frame(frame, canvas)
        run.report(StepProgress("reading", i + 1, count, run.elapsed(), None, {}))
    log.info("read %d frames in %.1f s", count, run.elapsed())
    drawn = run.reference.details if run.reference.details is not None else run.reference.track
    data = ReferenceData(store, image_to_canvas(drawn.joints, canvas), usable, canvas.size, layout=drawn.layout,
                         faces=run.config.uses_faces)
    if run.config.face_pass:
        if data.face_radius is None:
            log.info("the reference's poses have no face points: no face pass is trained")
        run.reference = replace(run.reference, face_radius=data.face_radius)
    return data


def _add_plate(run: TrainingRun, data: ReferenceData, previous: ReferenceModel | None) -> None:
    """Give the run and its data the background plate when the run trains with one: a resumed model keeps
    the plate its generator learnt to composite over, a new one estimates it from the frames just read."""
    if not run.config.background:
        return
    plate = previous.plate if previous is not None else None
    if plate is None:
        plate = reference_plate(data, run.config.plate)
    data.plate = plate
    run.reference = replace(run.reference, plate=plate)


def _add_exemplars(run: TrainingRun, data: ReferenceData, previous: ReferenceModel | None, fps: float) -> None:
    """Give a run whose generator reads exemplars its bank (a resumed model keeps its own, a new one chooses it
    from the frames just read) and its data each frame's candidates (:mod:`clone.model.exemplar`)."""
    if not run.config.exemplar:
        return
    bank = previous.exemplars if previous is not None else None
    if bank is None:
        bank = choose_bank(data.frames, data.joints, data.usable)
    # a second away, or a quarter of a short reference's frames
    gap = max(1, min(round(GAP_SECONDS * fps), len(data.indices) // 4))
    data.set_exemplars(bank, gap=gap)
    run.reference = replace(run.reference, exemplars=bank)
    log.info("exemplars from %d of the reference's frames", len(bank))


def _train_steps(
    run: TrainingRun, data: ReferenceData, rows: np.ndarray, steps: int | None, limit_s: float | None,
    grow: ThreadGrowth | None = None,
) -> tuple[dict[str, float], bool]:
    """Step until ``steps`` in total or ``limit_s`` seconds; returns ``(last losses, interrupted)``.

    The losses are means over the global batch. Whether the time is up, or a periodic save due, is decided on
    rank 0's clock and shared with the losses, so that every process stops (and waits for a save) together.
    """
    trainer, config, world = run.trainer, run.config, run.world
    losses: dict[str, float] = {}
    last_save = time.perf_counter()
    samples = config.batch_size if run.part is None else run.part.stop - run.part.start

    def time_up() -> bool:
        return world.is_main and limit_s is not None and run.elapsed() >= limit_s

    def progress() -> float:  # share of the budget used: this call's time, or the total steps, whichever ends first
        shares = [0.0]
        if limit_s:
            shares.append(run.elapsed() / limit_s)
        if steps:  # steps count from the model's first (a resumed run to N steps in all equals one run of N)
            shares.append(trainer.step_count / steps)
        return min(1.0, max(shares))

    stop = distributed.any_rank(time_up())
    # the budget's share used, as every process sees it (rank 0's clock and steps); at the start, the steps'
    done = min(1.0, trainer.step_count / steps) if steps else 0.0
    try:
        while (steps is None or trainer.step_count < steps) and not stop:
            trainer.set_lr(config.lr_factor(done))
            losses = _one_step(run, data)
            if grow is not None:
                grow()
            save_due = world.is_main and time.perf_counter() - last_save > config.save_every_s
            # rank 0's share rides with the losses, so that every process sets the same learning rate: the
            # mean over ranks weights each by its samples, which add up to the batch, and only rank 0 gives one
            losses["_done"] = progress() * config.batch_size / samples if world.is_main else 0.0
            losses, (stop, save_due) = distributed.reduce_logs(losses, samples, [time_up(), save_due])
            done = losses.pop("_done")
            if trainer.step_count % config.preview_every == 0 and world.is_main:
                write_png(preview_grid(trainer, data, rows), preview_path(run.out))
            if save_due:
                run.save()
                last_save = time.perf_counter()
            run.report(StepProgress("training", trainer.step_count, steps, run.elapsed(), limit_s, losses))
    except KeyboardInterrupt:
        log.warning("interrupted at step %d; saving", trainer.step_count)
        return losses, True
    return losses, False


def _one_step(run: TrainingRun, data: ReferenceData) -> dict[str, float]:
    """One augmented batch (this process's part of it), one update of G and D; this part's mean losses.

    The random numbers of the whole batch are drawn on every process, each keeps those of its part.
    """
    config, rng, trainer = run.config, run.rng, run.trainer
    total = config.batch_size
    part = slice(0, total) if run.part is None else run.part
    pick = torch.randint(len(data.indices), (total,), generator=rng).numpy()
    matrices = random_affines(total, data.size, config.augment, rng)  # [total, 2, 3]
    offsets = None
    if config.augment.pose_jitter and data.height:  # drawn only when asked, so runs without it draw as before
        noise = torch.randn(total, data.joints.shape[1], 2, generator=rng).numpy()  # [total, J, 2]
        offsets = (noise * config.augment.pose_jitter * data.height)[part]
    mirror = None
    if config.augment.mirror:  # drawn only when asked, so runs without it draw as before
        mirror = (torch.rand(total, generator=rng) < config.augment.mirror).numpy()
    exemplar_pick = exemplar_drop = None
    if data.exemplar_choices is not None:  # drawn only with exemplars, so runs without them draw as before
        exemplar_pick = torch.randint(data.exemplar_choices.shape[1], (total,), generator=rng).numpy()[part]
        if config.augment.exemplar_drop:
            limb = torch.randint(len(LIMBS), (total,), generator=rng).numpy()
            dropped = (torch.rand(total, generator=rng) < config.augment.exemplar_drop).numpy()
            exemplar_drop = np.where(dropped, limb, -1)[part]
    idx = data.indices[pick]
    sample = warp_batch(data.batch(idx[part], offsets, None if mirror is None else mirror[part], exemplar_pick,
                                   exemplar_drop), matrices[part])
    if config.augment.person_crop:  # drawn only when asked, so runs without it draw as before
        # one window around the whole batch's people (both frames of each sample), the same on every process
        flips = np.zeros(total, bool) if mirror is None else mirror
        points = np.stack([np.concatenate([data.frame_joints(i, f), data.frame_joints(max(i - 1, 0), f)])
                           for i, f in zip(idx, flips)])  # [total, 2J, 2]
        window = person_window(warped_points(points, matrices), data.size, 2 ** trainer.g.config.depth, rng)
        if float(torch.rand(1, generator=rng)) >= WHOLE_CANVAS_SHARE:
            sample = crop(sample, window)
    pin = trainer.device.type == "cuda"
    sample = {k: (v.pin_memory() if pin else v).to(trainer.device, non_blocking=pin) for k, v in sample.items()}
    prev_input, fake_prev = trainer.previous_input(sample, rng, part, total)
    weight = distributed.shard_weight(part, total, run.world)
    return trainer.train_step(sample, prev_input, fake_prev, weight)
