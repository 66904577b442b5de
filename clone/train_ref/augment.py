"""Augmentation of training samples: one random affine warp shared by pose maps and frames, and the degraded
previous-frame input G learns to correct.

Tensors are ``[B, 3, S, S]`` float in [-1, 1]; random numbers come from a CPU ``torch.Generator`` passed in, so
a run (and a resumed run) draws the same numbers on every device.
"""

from __future__ import annotations

import torch
from torch import Tensor

from clone.train_ref.config import AugmentConfig


def random_affines(batch: int, size: int, cfg: AugmentConfig, generator: torch.Generator) -> Tensor:
    """[B, 2, 3] pixel affine matrices: small rotation and zoom about the centre, plus a shift."""
    u = torch.rand(batch, 4, generator=generator) * 2.0 - 1.0  # [B, 4] in [-1, 1]
    angle = torch.deg2rad(u[:, 0] * cfg.rotation_deg)
    scale = 1.0 + u[:, 1] * cfg.scale
    shift = u[:, 2:] * cfg.translate * size  # [B, 2]
    c = (size - 1) / 2.0
    cos, sin = torch.cos(angle) * scale, torch.sin(angle) * scale
    m = torch.zeros(batch, 2, 3)
    m[:, 0, 0], m[:, 0, 1] = cos, -sin
    m[:, 1, 0], m[:, 1, 1] = sin, cos
    m[:, 0, 2] = c - cos * c + sin * c + shift[:, 0]
    m[:, 1, 2] = c - sin * c - cos * c + shift[:, 1]
    return m


def warp_batch(sample: dict[str, Tensor], matrices: Tensor) -> dict[str, Tensor]:
    """Warp pose maps, frames and the background plate (when the sample has one) with the same [B, 2, 3]
    matrices (kornia): the plate stays the background of the warped frames.

    Pose maps (and the face mask, when there is one) are padded with black (-1; 0), frames and plate by repeating
    their border.
    """
    from kornia.geometry.transform import warp_affine

    size = sample["pose_cur"].shape[-1]
    m = matrices.to(sample["pose_cur"].device)
    out = dict(sample)
    poses = torch.cat([sample["pose_prev"], sample["pose_cur"]], dim=1) + 1.0  # [B, 6, S, S], black = 0
    poses = warp_affine(poses, m, (size, size), padding_mode="zeros", align_corners=True) - 1.0
    out["pose_prev"], out["pose_cur"] = poses[:, :3], poses[:, 3:]
    names = ["frame_prev", "frame_cur"] + (["plate"] if "plate" in sample else [])
    frames = torch.cat([sample[n] for n in names], dim=1)  # [B, 6 or 9, S, S]
    frames = warp_affine(frames, m, (size, size), padding_mode="border", align_corners=True)
    for i, name in enumerate(names):
        out[name] = frames[:, 3 * i:3 * i + 3]
    out["frame_prev"] = torch.where(sample["has_prev"].to(m.device)[:, None, None, None], out["frame_prev"], 0.0)
    if "face" in sample:
        out["face"] = warp_affine(sample["face"], m, (size, size), padding_mode="zeros", align_corners=True)
    return out


def degrade_previous(
    prev: Tensor, has_prev: Tensor, cfg: AugmentConfig, dropout: float, generator: torch.Generator
) -> Tensor:
    """The previous-frame input as G gets it: colour-jittered, noisy, sometimes zeros.

    Args:
        prev: [B, 3, S, S] in [-1, 1].
        has_prev: [B] bool; samples without a previous frame get exact zeros, as the first driven frame does.
        cfg: augmentation settings.
        dropout: probability of replacing a sample's previous frame by zeros.
        generator: CPU random generator.

    Returns:
        [B, 3, S, S].
    """
    from kornia.enhance import adjust_brightness, adjust_contrast, adjust_saturation

    b = prev.shape[0]
    u = (torch.rand(b, 3, generator=generator) * 2.0 - 1.0).to(prev.device)  # [B, 3]
    x = (prev + 1.0) / 2.0  # [0, 1]
    x = adjust_brightness(x, u[:, 0] * cfg.prev_jitter)
    x = adjust_contrast(x, 1.0 + u[:, 1] * cfg.prev_jitter)
    x = adjust_saturation(x, 1.0 + u[:, 2] * cfg.prev_jitter)
    x = x.clamp(0, 1) * 2.0 - 1.0
    noise = torch.randn(prev.shape, generator=generator).to(prev.device) * cfg.prev_noise
    keep = (torch.rand(b, generator=generator) >= dropout).to(prev.device) & has_prev.to(prev.device)
    keep = keep[:, None, None, None]
    return torch.where(keep, x + noise, torch.zeros_like(x))
