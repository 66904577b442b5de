"""Training the retargeting network on the synthetic motion world (Aberman et al. 2019, Sec. 4-5).

Each sample draws two (motion, character, view) triples from a split of :mod:`retarget.world` and the
windows of all 8 combinations; the batch is augmented (:mod:`retarget.augment`) and the objective of
:mod:`retarget.losses` is minimised with AMSGrad. Optional real tracks (OpenPose folders) add a
self-reconstruction term. One checkpoint file (:mod:`retarget.checkpoint`) is rewritten atomically after
every epoch and when the time budget ends; ``resume=True`` continues it exactly where it stopped.

Under ``torchrun`` (:mod:`retarget.distributed`) every process trains its part of each global batch of
``batch_size`` samples in DistributedDataParallel; rank 0 writes the checkpoint, which resumes under any
number of processes. On CUDA the network runs in bfloat16 autocast (``amp``).

The split interface used here (the motion world provides it)::

    split.num_motions, split.num_characters, split.num_views
    split.window(motion, character, view, length=64, offset=0, rng=None) -> [length, 15, 2] float32
"""

from __future__ import annotations

import copy
import dataclasses
import logging
import math
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

import numpy as np
import torch
from torch import nn
from torch.utils.data import DataLoader, Dataset

from pose_io.errors import InputError
from pose_io.measures import skeleton_heights
from pose_io.track import PoseTrack
from retarget import distributed
from retarget.augment import COMBOS, AugmentConfig, augment_targets, corrupt_inputs
from retarget.checkpoint import RetargetWeights, load_checkpoint, load_weights, save_checkpoint, unwrap
from retarget.losses import LossConfig, objective, self_reconstruction
from retarget.model import RetargetNet, variant_config
from retarget.preprocess import (
    LAYOUT,
    LOCAL_INDEX,
    NormStats,
    PreprocessConfig,
    joints_to_channels,
    prepare_track,
    row_statistics,
)

log = logging.getLogger(__name__)

CPU = torch.device("cpu")
DEFAULT_EPOCHS = 300  # the authors' schedule, used when neither epochs nor minutes are given


class WorldSplit(Protocol):
    """What training needs from a split of the motion world."""

    num_motions: int
    num_characters: int
    num_views: int

    def window(
        self, motion: int, character: int, view: int, length: int = 64, offset: int = 0,
        rng: np.random.Generator | None = None,
    ) -> np.ndarray: ...


@dataclass(frozen=True)
class TrainConfig:
    """Everything that decides what is learned (defaults: the paper's / the authors' settings).

    Attributes:
        variant: network variant (:data:`retarget.model.VARIANTS`).
        window: frames per training window (the longest clip length).
        batch_size: samples per step (each sample has 8 windows).
        lr: Adam learning rate.
        amsgrad: use the AMSGrad variant.
        lr_decay: learning-rate factor per epoch.
        samples_per_epoch: random samples per epoch (validation and a checkpoint follow every epoch).
        val_samples: fixed validation samples (from the "val" split).
        stats_windows: random training windows the normalisation statistics are computed from.
        real_batch_size: real-track windows per step (when real tracks are given).
        real_weight: weight of their self-reconstruction loss.
        seed: seed of every random choice.
        augment: augmentation settings.
        loss: objective settings (see :data:`retarget.losses.ABLATIONS`).
        preprocess: canvas and smoothing used at inference (stored in the checkpoint).
        body_normalise: bring every character to one skeleton height in training, and every track to it at
            inference, instead of scaling by the image height (the target height is that of the initial
            weights' mean pose, or the median character's; stored in the checkpoint's preprocessing).
    """

    variant: str = "full"
    window: int = 64
    batch_size: int = 64
    lr: float = 1e-3
    amsgrad: bool = True
    lr_decay: float = 0.99
    samples_per_epoch: int = 6400
    val_samples: int = 256
    stats_windows: int = 2048
    real_batch_size: int = 16
    real_weight: float = 1.0
    seed: int = 0
    augment: AugmentConfig = field(default_factory=AugmentConfig)
    loss: LossConfig = field(default_factory=LossConfig)
    preprocess: PreprocessConfig = field(default_factory=PreprocessConfig)
    body_normalise: bool = True
    extra_characters: int = 0
    extra_spread: float = 1.0

    def __post_init__(self) -> None:
        variant_config(self.variant)  # ValueError for an unknown name
        if self.window % 8 or max(self.augment.clip_lengths) > self.window:
            raise ValueError("window must be a multiple of 8 and at least every clip length")
        if self.batch_size <= 0:
            raise ValueError("batch_size must be positive")

    def to_dict(self) -> dict[str, Any]:
        """Nested plain dict (lists for tuples)."""
        def plain(value: Any) -> Any:
            if isinstance(value, dict):
                return {k: plain(v) for k, v in value.items()}
            return list(value) if isinstance(value, tuple) else value

        return plain(dataclasses.asdict(self))

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> TrainConfig:
        """Inverse of :meth:`to_dict`."""
        nested = {"augment": AugmentConfig, "loss": LossConfig, "preprocess": PreprocessConfig}
        values = dict(data)
        for key, kind in nested.items():
            if key in values:
                values[key] = kind(**{k: tuple(v) if isinstance(v, list) else v for k, v in values[key].items()})
        return cls(**values)


# ---------------------------------------------------------------------------------------------------------
# Data


class CrossSamples(Dataset):
    """Samples of two (motion, character, view) triples and the windows of their 8 combinations.

    Sample ``index`` of epoch ``epoch`` is a pure function of (seed, epoch, index), so training resumes
    exactly and data-loader workers need no shared state. The two motions always differ; characters
    (views) differ when the network has a skeleton (view) encoder, and are shared otherwise. Every
    window of one view is seen through the same camera (the world's ``rng`` draws the camera pitch).

    Args:
        split: a world split.
        length: frames per window.
        variant: network variant.
        size: samples per epoch.
        seed: seed.
        scales: optional [C] factor per character (body-height normalisation), applied about the origin.
    """

    def __init__(
        self, split: WorldSplit, length: int, variant: str, size: int, seed: int, scales: np.ndarray | None = None
    ) -> None:
        if split.num_motions < 2:
            raise InputError(f"the motion world split has {split.num_motions} motion(s); training needs 2 or more")
        config = variant_config(variant)
        self.split = split
        self.length = length
        self.size = size
        self.seed = seed
        self.scales = scales
        self.epoch = 0
        self.vary_character = config.body_channels is not None and split.num_characters > 1
        self.vary_view = config.view_channels is not None and split.num_views > 1

    def __len__(self) -> int:
        return self.size

    def sample(self, epoch: int, index: int) -> dict[str, np.ndarray]:
        """{"windows": [8, length, 15, 2] float32 (order of :data:`COMBOS`), "ids": [2, 3] int64}."""
        rng = np.random.default_rng([self.seed, epoch, index])
        motions = rng.choice(self.split.num_motions, 2, replace=False)
        chars = _pair(rng, self.split.num_characters, self.vary_character)
        views = _pair(rng, self.split.num_views, self.vary_view)
        # The world's `rng` perturbs the camera (pitch): a fresh generator per view slot gives every
        # window seen from one view the same camera.
        view_seeds = rng.integers(0, 2**63 - 1, size=2)
        if views[0] == views[1]:
            view_seeds[1] = view_seeds[0]
        cache: dict[tuple[int, int, int], np.ndarray] = {}
        windows = []
        for m, c, v in COMBOS:
            key = (int(motions[m]), int(chars[c]), int(views[v]))
            if key not in cache:
                camera = np.random.default_rng(int(view_seeds[v]))
                window = self.split.window(*key, length=self.length, offset=0, rng=camera)
                if self.scales is not None:
                    window = window * self.scales[key[1]]
                cache[key] = np.asarray(window, np.float32)
            windows.append(cache[key])
        ids = np.stack([motions, chars, views], axis=1).astype(np.int64)  # [2, 3]
        return {"windows": np.stack(windows), "ids": ids}

    def __getitem__(self, index: int) -> dict[str, np.ndarray]:
        return self.sample(self.epoch, index)


def _pair(rng: np.random.Generator, n: int, distinct: bool) -> np.ndarray:
    if distinct:
        return rng.choice(n, 2, replace=False)
    return np.repeat(rng.integers(n), 2)


def split_statistics(
    split: WorldSplit, length: int, count: int, seed: int, scales: np.ndarray | None = None
) -> NormStats:
    """Normalisation statistics of ``count`` random windows of a split (each scaled by its character's factor)."""
    rng = np.random.default_rng([seed, 7919])
    windows = []
    for _ in range(count):
        m, c, v = (int(rng.integers(n)) for n in (split.num_motions, split.num_characters, split.num_views))
        window = split.window(m, c, v, length=length, offset=0, rng=rng)
        windows.append(window * (1.0 if scales is None else scales[c]))
    return row_statistics(np.stack(windows))


def character_heights(split: WorldSplit, length: int, per_character: int, seed: int) -> np.ndarray:
    """[C] median skeleton height (canvas pixels) of each character over ``per_character`` random windows."""
    rng = np.random.default_rng([seed, 3571])
    heights = np.empty(split.num_characters)
    for c in range(split.num_characters):
        windows = np.stack([
            split.window(int(rng.integers(split.num_motions)), c, int(rng.integers(split.num_views)),
                         length=length, offset=0, rng=rng)
            for _ in range(per_character)
        ])  # fmt: skip
        heights[c] = np.nanmedian(skeleton_heights(windows, LAYOUT))
    return heights


def mean_pose_height(stats: NormStats) -> float:
    """Skeleton height of the mean pose that normalisation statistics describe (canvas pixels)."""
    joints = np.zeros((1, 1, len(LAYOUT), 2))
    joints[0, 0, list(LOCAL_INDEX)] = stats.mean[:-1]
    return float(skeleton_heights(joints, LAYOUT)[0])


def body_scales(split: WorldSplit, config: TrainConfig, target: float) -> np.ndarray | None:
    """[C] factor bringing each character of ``split`` to ``target`` skeleton height (None: no normalisation)."""
    if not config.body_normalise:
        return None
    return target / character_heights(split, config.window, 8, config.seed)


def real_windows(tracks: Sequence[PoseTrack], length: int, preprocess: PreprocessConfig) -> np.ndarray:
    """Overlapping windows (half-window steps) of real tracks in the canvas: [N, length, 15, 2] float32."""
    out = []
    for i, track in enumerate(tracks):
        if len(track) < length:
            log.warning("real track %d has %d frames (< %d); skipped", i, len(track), length)
            continue
        joints = prepare_track(track, preprocess, f"real track {i}")
        out += [joints[s : s + length] for s in range(0, len(joints) - length + 1, max(1, length // 2))]
    return np.asarray(out, dtype=np.float32).reshape(-1, length, 15, 2)


def read_real_tracks(folder: str | Path, named: bool = False) -> list:
    """Every OpenPose folder in ``folder`` (or ``folder`` itself when it holds the JSON files).

    Returns:
        the tracks, or ``(folder name, track)`` pairs with ``named``.
    """
    from pose_io.readers import read_track

    folder = Path(folder)
    if not folder.is_dir():
        raise InputError(f"{folder}: not a folder of OpenPose folders")
    if any(folder.glob("*_keypoints.json")):
        subfolders = [folder]
    else:
        subfolders = sorted(p for p in folder.iterdir() if p.is_dir() and any(p.glob("*_keypoints.json")))
    if not subfolders:
        raise InputError(f"{folder}: no OpenPose folders (*_keypoints.json) in it")
    tracks = [read_track(p, fmt="openpose") for p in subfolders]
    return [(p.name, t) for p, t in zip(subfolders, tracks)] if named else tracks


# ---------------------------------------------------------------------------------------------------------
# One step


def batch_tensors(
    windows: torch.Tensor, ids: torch.Tensor, stats: NormStats, config: TrainConfig, generator: torch.Generator,
    augment: bool = True,
) -> tuple[torch.Tensor, torch.Tensor]:
    """Network inputs and targets of a batch of samples.

    Args:
        windows: [B, 8, T, 15, 2] canvas pixels.
        ids: [B, 2, 3] triple ids.
        stats: normalisation statistics.
        config: settings.
        generator: random source.
        augment: clip/scale/flip and corrupt (False for validation).

    Returns:
        (inputs, targets), each [B, 8, 30, T'].
    """
    if augment:
        windows = augment_targets(windows, ids, config.augment, generator)
    b, k, t = windows.shape[:3]
    flat = windows.reshape(b * k, t, *windows.shape[3:])  # [B*8, T', 15, 2]
    noisy = corrupt_inputs(flat, config.augment.noise_std, config.augment.drop_prob, generator) if augment else flat
    targets = joints_to_channels(flat, stats).reshape(b, k, -1, t)  # [B, 8, 30, T']
    inputs = joints_to_channels(noisy, stats).reshape(b, k, -1, t)
    return inputs, targets


def part_tensors(
    windows: torch.Tensor, ids: torch.Tensor, stats: NormStats, config: TrainConfig, generator: torch.Generator,
    part: slice, total: int,
) -> tuple[torch.Tensor, torch.Tensor]:
    """Network inputs and targets of one rank's part of a global batch, augmented as one process would.

    The augmentation draws its random numbers for a whole batch at once, sample after sample. This rank's
    samples are put at ``part`` of a batch of ``total`` samples (zeros elsewhere), so they get exactly the
    numbers a single process gives them and the generator ends in the same state on every rank; the zero
    samples cost elementwise work only.

    Args:
        windows: [n, 8, T, 15, 2] the samples at ``part`` (canvas pixels).
        ids: [n, 2, 3] their triple ids.
        stats: normalisation statistics.
        config: settings.
        generator: random source, in the same state on every rank.
        part: where the samples sit in the global batch.
        total: samples in the global batch.

    Returns:
        (inputs, targets), each [n, 8, 30, T'].
    """
    if (part.start, part.stop) == (0, total):
        return batch_tensors(windows, ids, stats, config, generator)
    full = windows.new_zeros((total, *windows.shape[1:]))  # [total, 8, T, 15, 2]
    full[part] = windows
    full_ids = ids.new_zeros((total, *ids.shape[1:]))  # [total, 2, 3]
    full_ids[part] = ids
    inputs, targets = batch_tensors(full, full_ids, stats, config, generator)
    return inputs[part], targets[part]


class TrainLoss(nn.Module):
    """The loss of one step as ONE module call, which is what DistributedDataParallel wraps.

    The objective calls several methods of the network (the encoders, the decoder); DistributedDataParallel
    only sees calls of ``forward``, so the whole objective is this module's forward.

    Args:
        net: the network.
        stats: normalisation statistics.
        config: settings.
    """

    def __init__(self, net: RetargetNet, stats: NormStats, config: TrainConfig) -> None:
        super().__init__()
        self.net = net
        self.stats = stats
        self.config = config

    def forward(
        self, inputs: torch.Tensor, targets: torch.Tensor, real_inputs: torch.Tensor | None = None,
        real_targets: torch.Tensor | None = None, weight: float = 1.0,
    ) -> tuple[dict[str, torch.Tensor], torch.Tensor]:
        """Loss terms and what to minimise.

        Args:
            inputs: [B, 8, 30, T] normalised, corrupted network inputs.
            targets: [B, 8, 30, T] normalised ground truth.
            real_inputs: optional [R, 30, T] corrupted real-track windows (self-reconstruction).
            real_targets: [R, 30, T] their clean windows.
            weight: factor of the synthetic batch's mean loss (:func:`retarget.distributed.shard_weight`).

        Returns:
            ``(terms, objective)``: the terms as logged (means of this batch), and
            ``weight * synthetic total + real term``.
        """
        cfg = self.config
        losses = objective(self.net, inputs, targets, self.stats, cfg.loss)
        minimise = losses["total"] if weight == 1.0 else weight * losses["total"]
        if real_inputs is not None and real_targets is not None:
            real = self_reconstruction(self.net, real_inputs, real_targets, self.stats, cfg.loss)
            losses["real"] = cfg.real_weight * real["total"]
            losses["total"] = losses["total"] + losses["real"]
            minimise = minimise + losses["real"]
        return losses, minimise


def train_step(
    model: nn.Module, optimizer: torch.optim.Optimizer, batch: dict[str, torch.Tensor], stats: NormStats,
    config: TrainConfig, generator: torch.Generator, real: torch.Tensor | None = None, *,
    part: slice | None = None, total: int | None = None, dtype: torch.dtype | None = None,
) -> dict[str, float]:
    """One optimisation step; returns the loss terms of this process's samples as floats.

    Args:
        model: the network, or its :class:`TrainLoss` (in DistributedDataParallel when several processes
            train); put in train mode.
        optimizer: its optimizer.
        batch: {"windows": [n, 8, T, 15, 2], "ids": [n, 2, 3]} on the model's device: the batch, or this
            process's ``part`` of a global batch.
        stats: normalisation statistics.
        config: settings.
        generator: random source of augmentation (in the same state on every process).
        real: optional [R, T, 15, 2] real-track windows for the self-reconstruction term (all of them on
            every process: their term is small, and so the global step equals one process's).
        part: where ``batch`` sits in the global batch (default: it is the whole batch).
        total: samples in the global batch (default: those of ``batch``).
        dtype: autocast dtype (bfloat16 on CUDA), None for float32.
    """
    loss_fn = model if isinstance(unwrap(model), TrainLoss) else TrainLoss(model, stats, config)
    windows = batch["windows"]
    total = len(windows) if total is None else total
    # A part of the global batch weighs by its share; a whole batch is the same on every process (weight 1).
    weight = 1.0 if part is None else distributed.shard_weight(part, total, distributed.current())
    part = slice(0, total) if part is None else part
    loss_fn.train()
    inputs, targets = part_tensors(windows, batch["ids"], stats, config, generator, part, total)
    real_inputs = real_targets = None
    if real is not None and len(real):
        length = inputs.shape[-1]
        clipped = real[:, :length] if real.shape[1] == length else _clip_real(real, length, generator)
        noisy = corrupt_inputs(clipped, config.augment.noise_std, config.augment.drop_prob, generator)
        real_inputs, real_targets = joints_to_channels(noisy, stats), joints_to_channels(clipped, stats)
    with distributed.autocast(windows.device, dtype):
        losses, minimise = loss_fn(inputs, targets, real_inputs, real_targets, weight)
    optimizer.zero_grad(set_to_none=True)
    minimise.backward()
    optimizer.step()
    return {k: float(v.detach()) for k, v in losses.items()}


def _clip_real(real: torch.Tensor, length: int, generator: torch.Generator) -> torch.Tensor:
    offset = int(torch.randint(real.shape[1] - length + 1, (1,), generator=generator))
    return real[:, offset : offset + length]


@torch.no_grad()
def evaluate(
    model: RetargetNet, windows: torch.Tensor, ids: torch.Tensor, stats: NormStats, config: TrainConfig,
    batch_size: int = 64, dtype: torch.dtype | None = None,
) -> dict[str, float]:
    """Mean loss terms over fixed validation samples (eval mode, no augmentation; ``dtype``: autocast)."""
    model.eval()
    device = next(model.parameters()).device
    sums: dict[str, float] = {}
    for start in range(0, len(windows), batch_size):
        w, i = windows[start : start + batch_size].to(device), ids[start : start + batch_size].to(device)
        inputs, targets = batch_tensors(w, i, stats, config, torch.Generator(), augment=False)
        with distributed.autocast(device, dtype):
            terms = objective(model, inputs, targets, stats, config.loss)
        for k, v in terms.items():
            sums[k] = sums.get(k, 0.0) + float(v) * len(w)
    return {k: v / len(windows) for k, v in sums.items()}


# ---------------------------------------------------------------------------------------------------------
# The loop


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
    """

    checkpoint: Path
    epochs: int
    steps: int
    stopped: str
    history: list[dict[str, float]]


def fit(
    train_split: WorldSplit,
    val_split: WorldSplit | None,
    out: str | Path,
    config: TrainConfig = TrainConfig(),
    device: torch.device = CPU,
    real_tracks: Sequence[PoseTrack] = (),
    epochs: int | None = None,
    minutes: float | None = None,
    resume: bool = False,
    num_workers: int = 0,
    progress: ProgressFn | None = None,
    init: RetargetWeights | None = None,
    amp: bool | None = None,
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

    Returns:
        A :class:`TrainSummary` (the same on every process).

    Raises:
        InputError: ``out`` exists without ``resume``, holds a run with other settings, or the batch is
            smaller than the number of processes.
    """
    out = Path(out)
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
    step_loss = distributed.wrap(TrainLoss(model, stats, config), dev)  # DDP with several processes
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
    step_in_epoch: int = done.get("step", 0)
    global_step: int = done.get("global_step", 0)
    elapsed_before: float = done.get("elapsed_s", 0.0)
    history: list[dict[str, float]] = list(done.get("history", []))

    size = config.samples_per_epoch
    dataset = CrossSamples(train_split, config.window, config.variant, size, config.seed, scales)
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
            })
        distributed.barrier()

    def report(update: TrainProgress) -> None:
        if progress is not None and world.is_main:
            progress(update)

    stopped = "epochs"
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
        save()
        report(TrainProgress(epoch, steps_per_epoch, steps_per_epoch, global_step, record))
        if world.is_main:
            log.info("epoch %d: %s", epoch, _format(record))
        if distributed.any_rank(time.monotonic() > deadline):
            stopped = "time" if epoch < target_epochs else "epochs"
            break
    return TrainSummary(out, epoch, global_step, stopped, history)


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


def _validation_set(
    split: WorldSplit, config: TrainConfig, scales: np.ndarray | None
) -> tuple[torch.Tensor, torch.Tensor] | None:
    if split.num_motions < 2:
        log.warning("validation split has fewer than 2 motions; no validation")
        return None
    samples = CrossSamples(split, config.window, config.variant, config.val_samples, config.seed + 1, scales)
    items = [samples.sample(0, i) for i in range(config.val_samples)]
    windows = torch.from_numpy(np.stack([it["windows"] for it in items]))  # [N, 8, T, 15, 2]
    ids = torch.from_numpy(np.stack([it["ids"] for it in items]))  # [N, 2, 3]
    return windows, ids


def _loader(
    dataset: CrossSamples, first_step: int, steps: int, batch_size: int, workers: int, part: slice | None = None,
    pin: bool = False,
) -> Iterator:
    """Batches of steps ``first_step`` to ``steps``; with ``part``, this process's samples of each global batch.

    Step s of an epoch is samples ``[s * batch_size, (s + 1) * batch_size)`` whatever the number of
    processes; a process takes ``part`` of them.
    """
    if part is None or (part.start, part.stop) == (0, batch_size):
        indices: Sequence[int] = range(first_step * batch_size, steps * batch_size)
        per_step = batch_size
    else:
        indices = [s * batch_size + i for s in range(first_step, steps) for i in range(part.start, part.stop)]
        per_step = part.stop - part.start
    # Its own generator: a loader would otherwise draw its worker seed from the global RNG, and a resumed
    # run would then drop out differently. Samples depend on (seed, epoch, index) only.
    loader = DataLoader(dataset, batch_size=per_step, sampler=indices, num_workers=workers, drop_last=True,
                        generator=torch.Generator(), pin_memory=pin)
    return iter(loader)


def _format(losses: dict[str, float], prefix: str = "") -> str:
    keys = [k for k in losses if k.startswith(prefix) and k not in ("epoch", "seconds")]
    return " ".join(f"{k}={losses[k]:.4f}" for k in keys)


def train(
    mocap_dir: str | Path,
    out: str | Path,
    *,
    cache_dir: str | Path | None = None,
    real_dir: str | Path | None = None,
    config: TrainConfig = TrainConfig(),
    device: torch.device = CPU,
    epochs: int | None = None,
    minutes: float | None = None,
    resume: bool = False,
    num_workers: int = 0,
    progress: ProgressFn | None = None,
    init: str | Path | None = None,
    amp: bool | None = None,
) -> TrainSummary:
    """Build (or reuse the cache of) the motion world from ``mocap_dir`` and :func:`fit` on it.

    Under ``torchrun`` every process calls this (see :func:`fit`); the first process of each machine builds
    the world's cache while the others wait, then they read it.

    Args:
        mocap_dir: motion-capture folder the world is built from.
        out: checkpoint file.
        cache_dir: where the world is cached (default: the world's, ``~/.cache/clone2d/world``).
        real_dir: optional folder of OpenPose folders (unlabelled real tracks).
        config: training settings.
        device: where to train.
        epochs: total epochs (see :func:`fit`).
        minutes: time budget of this call.
        resume: continue the run in ``out``.
        num_workers: data-loader worker processes (cutting world windows overlaps the network's work).
        progress: callback (see :func:`fit`).
        init: checkpoint to start from: ours, or the authors' ``pretrained_*.pth`` with its statistics.
        amp: bfloat16 autocast on CUDA (see :func:`fit`).
    """
    from retarget.world import MotionWorld

    out = Path(out)
    if resume and not out.exists():
        raise InputError(f"{out}: nothing to resume (no such checkpoint)")
    if not resume:
        _require_new(out)
    start = load_weights(init) if init is not None and not resume else None
    real = read_real_tracks(real_dir) if real_dir is not None else []
    with distributed.main_first():
        world = MotionWorld.build(mocap_dir, cache_dir, seed=config.seed, extra_train_characters=config.extra_characters,
                                  extra_spread=config.extra_spread)  # fmt: skip
    return fit(
        world.split("train"), world.split("val"), out, config, device, real, epochs, minutes, resume,
        num_workers=num_workers, progress=progress, init=start, amp=amp,
    )
