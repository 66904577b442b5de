"""Training augmentation on batches of body15 windows (torch, batched, seeded by a ``torch.Generator``).

A training sample holds the windows of all 8 combinations of two (motion, skeleton, view) triples,
``[B, 8, T, 15, 2]`` in canvas pixels, combination ``k`` = (motion ``k >> 2 & 1``, skeleton ``k >> 1 & 1``,
view ``k & 1``) (:data:`COMBOS`). Augmentations keep the combinations consistent with each other:

* temporal clipping: one length per batch from ``clip_lengths``, one offset per sample;
* scaling by ``s`` in ``scale_range``, the same for every window of one skeleton;
* left-right flip (x mirrored, left/right joints swapped), the same for every window of one motion;
* input corruption (network inputs only): Gaussian noise and dropped joints, which are held from the
  previous frame as the inference preprocessing fills gaps.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch

from retarget.preprocess import LAYOUT

# (motion, skeleton, view) index of each of the 8 windows of a sample.
COMBOS: tuple[tuple[int, int, int], ...] = tuple((m, c, v) for m in (0, 1) for c in (0, 1) for v in (0, 1))
MOTION, SKELETON, VIEW = 0, 1, 2


def combo_index(motion: int, skeleton: int, view: int) -> int:
    """Position of a (motion, skeleton, view) combination in :data:`COMBOS`."""
    return 4 * motion + 2 * skeleton + view


@dataclass(frozen=True)
class AugmentConfig:
    """Augmentation settings (defaults: the paper's).

    Attributes:
        clip_lengths: window lengths a batch is clipped to (multiples of 8, at most the sample length).
        scale_range: range of the per-skeleton scale factor.
        flip_prob: probability of mirroring a motion.
        noise_std: std of the Gaussian noise added to network inputs (canvas pixels).
        drop_prob: probability that an input joint is dropped in a frame.
    """

    clip_lengths: tuple[int, ...] = (64, 56, 48, 40)
    scale_range: tuple[float, float] = (0.5, 1.5)
    flip_prob: float = 0.5
    noise_std: float = 1.0
    drop_prob: float = 0.05

    def __post_init__(self) -> None:
        if not self.clip_lengths or any(n <= 0 or n % 8 for n in self.clip_lengths):
            raise ValueError("clip_lengths must be positive multiples of 8")
        lo, hi = self.scale_range
        if not 0 < lo <= hi:
            raise ValueError("scale_range must be 0 < low <= high")


def _uniform(shape: tuple[int, ...], generator: torch.Generator) -> torch.Tensor:
    return torch.rand(shape, generator=generator)


def clip_time(windows: torch.Tensor, length: int, generator: torch.Generator) -> torch.Tensor:
    """Cut ``length`` frames at a random offset per sample: [B, K, T, J, 2] -> [B, K, length, J, 2]."""
    b, _, t = windows.shape[:3]
    if length > t:
        raise ValueError(f"cannot clip {t}-frame windows to {length}")
    offsets = (_uniform((b,), generator) * (t - length + 1)).long().clamp(max=t - length)  # [B]
    frames = offsets[:, None] + torch.arange(length)  # [B, length]
    index = frames.to(windows.device)[:, None, :, None, None].expand(-1, windows.shape[1], -1, *windows.shape[3:])
    return torch.gather(windows, 2, index)


def _per_combo(values: torch.Tensor, factor: int) -> torch.Tensor:
    """[B, 2] values per triple -> [B, 8] the value of each combination's ``factor`` index."""
    pick = torch.tensor([c[factor] for c in COMBOS], device=values.device)  # [8]
    return values[:, pick]


def scale_skeletons(windows: torch.Tensor, scales: torch.Tensor) -> torch.Tensor:
    """Scale every window by its skeleton's factor.

    Args:
        windows: [B, 8, T, J, 2].
        scales: [B, 2] factor of skeleton 0 and 1 of each sample.
    """
    return windows * _per_combo(scales, SKELETON)[:, :, None, None, None]


def flip_motions(windows: torch.Tensor, flips: torch.Tensor) -> torch.Tensor:
    """Mirror (x -> -x, left <-> right joints) every window whose motion is flipped.

    Args:
        windows: [B, 8, T, 15, 2] body15.
        flips: [B, 2] bool, whether motion 0 / 1 of each sample is mirrored.
    """
    mirrored = windows[:, :, :, torch.as_tensor(LAYOUT.mirror)] * windows.new_tensor([-1.0, 1.0])
    chosen = _per_combo(flips, MOTION)[:, :, None, None, None]  # [B, 8, 1, 1, 1]
    return torch.where(chosen, mirrored, windows)


def corrupt_inputs(
    joints: torch.Tensor, noise_std: float, drop_prob: float, generator: torch.Generator
) -> torch.Tensor:
    """Noise and dropped joints for network inputs: [N, T, J, 2] -> [N, T, J, 2].

    A dropped joint takes its value from the last frame where it was kept (frame 0 is always kept), as
    :func:`retarget.preprocess.hold_fill` fills real gaps.
    """
    n, t, j, _ = joints.shape
    noisy = joints + noise_std * torch.randn(joints.shape, generator=generator).to(joints.device)
    dropped = _uniform((n, t, j), generator) < drop_prob  # [N, T, J]
    dropped[:, 0] = False
    frame = torch.arange(t)[None, :, None].expand(n, t, j)
    source = torch.where(dropped, torch.zeros_like(frame), frame).cummax(dim=1).values  # last kept frame
    index = source.to(joints.device)[..., None].expand(-1, -1, -1, 2)
    return torch.gather(noisy, 1, index)


def augment_targets(
    windows: torch.Tensor, ids: torch.Tensor, config: AugmentConfig, generator: torch.Generator
) -> torch.Tensor:
    """Clip, scale and flip a batch of 8-combination samples (the ground truth of every output).

    Args:
        windows: [B, 8, T, 15, 2] canvas pixels.
        ids: [B, 2, 3] (motion, skeleton, view) ids of the two triples; equal skeleton ids get equal scales.
        config: settings.
        generator: random source (CPU).

    Returns:
        [B, 8, T', 15, 2] with T' drawn from ``config.clip_lengths``.
    """
    b = windows.shape[0]
    lengths = [n for n in config.clip_lengths if n <= windows.shape[2]] or [windows.shape[2]]
    length = lengths[int(torch.randint(len(lengths), (1,), generator=generator))]
    out = clip_time(windows, length, generator)
    lo, hi = config.scale_range
    scales = lo + (hi - lo) * _uniform((b, 2), generator)  # [B, 2]
    same = (ids[:, 0, SKELETON] == ids[:, 1, SKELETON]).cpu()
    scales[:, 1] = torch.where(same, scales[:, 0], scales[:, 1])
    out = scale_skeletons(out, scales.to(out.device, out.dtype))
    flips = _uniform((b, 2), generator) < config.flip_prob
    same = (ids[:, 0, MOTION] == ids[:, 1, MOTION]).cpu()
    flips[:, 1] = torch.where(same, flips[:, 0], flips[:, 1])
    return flip_motions(out, flips.to(out.device))
