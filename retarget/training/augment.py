"""Training augmentation on batches of body15 windows (torch, batched, seeded by a ``torch.Generator``).

A training sample holds the windows of all 8 combinations of two (motion, skeleton, view) triples,
``[B, 8, T, 15, 2]`` in canvas pixels, combination ``k`` = (motion ``k >> 2 & 1``, skeleton ``k >> 1 & 1``,
view ``k & 1``) (:data:`COMBOS`). Augmentations keep the combinations consistent with each other:

* temporal clipping: one length per batch from ``clip_lengths``, one offset per sample;
* time warping: every window of one motion replayed at one speed in ``speed_range`` (linear
  interpolation between frames), so a motion is seen faster and slower than it was captured;
* scaling by ``s`` in ``scale_range``, the same for every window of one skeleton;
* left-right flip (x mirrored, left/right joints swapped), the same for all 8 windows of a sample: a
  mirrored motion seen from yaw θ is the mirror image seen from -θ, so flipping one motion of a sample but
  not the other would pair a view code of θ with a target seen from -θ and teach the network to average
  the two (the damped motion of earlier clone2d weights);
* camera roll: every window of one view rotated in the image plane by one angle within ``roll_deg``;
* input corruption (network inputs only): Gaussian noise and dropped joints, which are held from the
  previous frame as the inference preprocessing fills gaps.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch

from retarget.network.preprocess import LAYOUT

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
        flip_prob: probability of mirroring a sample.
        noise_std: std of the Gaussian noise added to network inputs (canvas pixels).
        drop_prob: probability that an input joint is dropped in a frame.
        speed_range: range of the per-motion playback speed (1 = as captured; (1, 1) = off).
        roll_deg: largest camera roll per view, degrees (0 = off).
    """

    clip_lengths: tuple[int, ...] = (64, 56, 48, 40)
    scale_range: tuple[float, float] = (0.5, 1.5)
    flip_prob: float = 0.5
    noise_std: float = 1.0
    drop_prob: float = 0.05
    speed_range: tuple[float, float] = (0.7, 1.4)
    roll_deg: float = 8.0

    def __post_init__(self) -> None:
        if not self.clip_lengths or any(n <= 0 or n % 8 for n in self.clip_lengths):
            raise ValueError("clip_lengths must be positive multiples of 8")
        lo, hi = self.scale_range
        if not 0 < lo <= hi:
            raise ValueError("scale_range must be 0 < low <= high")
        lo, hi = self.speed_range
        if not 0 < lo <= hi:
            raise ValueError("speed_range must be 0 < low <= high")
        if not 0 <= self.roll_deg < 90:
            raise ValueError("roll_deg must be in [0, 90)")


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


def warp_time(
    windows: torch.Tensor, length: int, speeds: torch.Tensor, generator: torch.Generator
) -> torch.Tensor:
    """Cut ``length`` frames replayed at a speed per motion: [B, 8, T, J, 2] -> [B, 8, length, J, 2].

    Frame ``i`` of a window whose motion plays at speed ``s`` is source time ``offset + s * i``
    (linear interpolation); one offset per sample, drawn so that every window stays inside the source.
    Speeds that would need more than ``T`` source frames are reduced to fit.

    Args:
        windows: [B, 8, T, J, 2].
        length: output frames.
        speeds: [B, 2] speed of motion 0 / 1 of each sample.
        generator: random source of the offsets.
    """
    b, _, t = windows.shape[:3]
    if length > t:
        raise ValueError(f"cannot clip {t}-frame windows to {length}")
    span = max(length - 1, 1)
    speeds = speeds.clamp(max=(t - 1) / span)  # [B, 2]
    per_window = _per_combo(speeds, MOTION)  # [B, 8]
    room = (t - 1) - speeds.max(dim=1).values * (length - 1)  # [B] frames left for the offset
    offsets = _uniform((b,), generator) * room.clamp(min=0)  # [B]
    times = offsets[:, None, None] + per_window[:, :, None] * torch.arange(length)  # [B, 8, length]
    times = times.clamp(0, t - 1)
    low = times.floor().long().clamp(max=t - 2) if t > 1 else times.floor().long()
    frac = (times - low).to(windows.dtype)
    high = (low + 1).clamp(max=t - 1)

    def take(index: torch.Tensor) -> torch.Tensor:
        full = index.to(windows.device)[..., None, None].expand(-1, -1, -1, *windows.shape[3:])
        return torch.gather(windows, 2, full)

    weight = frac.to(windows.device)[..., None, None]
    return take(low) * (1 - weight) + take(high) * weight


def roll_views(windows: torch.Tensor, angles: torch.Tensor) -> torch.Tensor:
    """Rotate every window in the image plane by its view's angle, about the canvas origin.

    Args:
        windows: [B, 8, T, J, 2].
        angles: [B, 2] radians of view 0 / 1 of each sample.
    """
    a = _per_combo(angles, VIEW).to(windows.device, windows.dtype)  # [B, 8]
    cos, sin = torch.cos(a)[:, :, None, None], torch.sin(a)[:, :, None, None]
    x, y = windows[..., 0], windows[..., 1]
    return torch.stack([cos * x - sin * y, sin * x + cos * y], dim=-1)


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
    :func:`pose_io.clean.hold_fill` fills real gaps.
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
    """Clip, warp, scale, flip and roll a batch of 8-combination samples (the ground truth of every output).

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
    lo, hi = config.speed_range
    if (lo, hi) == (1.0, 1.0):
        out = clip_time(windows, length, generator)
    else:
        speeds = lo * (hi / lo) ** _uniform((b, 2), generator)  # log-uniform: as many slower as faster
        out = warp_time(windows, length, speeds, generator)
    lo, hi = config.scale_range
    scales = lo + (hi - lo) * _uniform((b, 2), generator)  # [B, 2]
    same = (ids[:, 0, SKELETON] == ids[:, 1, SKELETON]).cpu()
    scales[:, 1] = torch.where(same, scales[:, 0], scales[:, 1])
    out = scale_skeletons(out, scales.to(out.device, out.dtype))
    flips = (_uniform((b, 1), generator) < config.flip_prob).expand(b, 2)  # both motions alike (see above)
    out = flip_motions(out, flips.to(out.device))
    if config.roll_deg > 0:
        angles = torch.deg2rad(config.roll_deg * (2 * _uniform((b, 2), generator) - 1))  # [B, 2]
        same = (ids[:, 0, VIEW] == ids[:, 1, VIEW]).cpu()
        angles[:, 1] = torch.where(same, angles[:, 0], angles[:, 1])
        out = roll_views(out, angles)
    return out
