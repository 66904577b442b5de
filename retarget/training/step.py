"""One optimisation step: the batch's tensors, the loss as one module call, the step, and validation."""

from __future__ import annotations

import torch
from torch import nn

from retarget.network.checkpoint import unwrap
from retarget.network.model import RetargetNet
from retarget.network.preprocess import NormStats, joints_to_channels
from retarget.training import distributed
from retarget.training.augment import augment_targets, corrupt_inputs
from retarget.training.config import TrainConfig
from retarget.training.losses import objective, self_reconstruction


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
        proportions: [C, P] the training characters' standardised log proportions (:func:`character_proportions`),
            for the skeleton-proportion term.
    """

    def __init__(
        self, net: RetargetNet, stats: NormStats, config: TrainConfig, proportions: torch.Tensor | None = None
    ) -> None:
        super().__init__()
        self.net = net
        self.stats = stats
        self.config = config
        self.proportions = proportions  # [C, P] the training characters' (skeleton-proportion term)

    def forward(
        self, inputs: torch.Tensor, targets: torch.Tensor, real_inputs: torch.Tensor | None = None,
        real_targets: torch.Tensor | None = None, weight: float = 1.0, ids: torch.Tensor | None = None,
    ) -> tuple[dict[str, torch.Tensor], torch.Tensor]:
        """Loss terms and what to minimise.

        Args:
            inputs: [B, 8, 30, T] normalised, corrupted network inputs.
            targets: [B, 8, 30, T] normalised ground truth.
            real_inputs: optional [R, 30, T] corrupted real-track windows (self-reconstruction).
            real_targets: [R, 30, T] their clean windows.
            weight: factor of the synthetic batch's mean loss (:func:`retarget.training.distributed.shard_weight`).
            ids: [B, 2, 3] the samples' triple ids.

        Returns:
            ``(terms, objective)``: the terms as logged (means of this batch), and
            ``weight * synthetic total + real term``.
        """
        cfg = self.config
        losses = objective(self.net, inputs, targets, self.stats, cfg.loss, ids, self.proportions)
        minimise = losses["total"] if weight == 1.0 else weight * losses["total"]
        if real_inputs is not None and real_targets is not None:
            real = self_reconstruction(self.net, real_inputs, real_targets, self.stats, cfg.loss)
            losses["real"] = cfg.real_weight * real["total"]
            losses["total"] = losses["total"] + losses["real"]
            minimise = minimise + losses["real"]
        return losses, minimise


def character_proportions(split) -> torch.Tensor:  # split: retarget.world.split.WorldSplit
    """[C, bones] float32: the split's characters' log(bone length / skeleton height), standardised over them."""
    from retarget.world.characters import standard_proportions

    return torch.from_numpy(standard_proportions(split.characters)).float()


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
        losses, minimise = loss_fn(inputs, targets, real_inputs, real_targets, weight, batch["ids"])
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
            terms = objective(model, inputs, targets, stats, config.loss, i)
        for k, v in terms.items():
            sums[k] = sums.get(k, 0.0) + float(v) * len(w)
    return {k: v / len(windows) for k, v in sums.items()}
