"""Augmentation of training samples: one random affine warp shared by pose maps and frames, and the degraded
previous-frame input G learns to correct.

Tensors are ``[B, 3, S, S]`` float in [-1, 1]; random numbers come from a CPU ``torch.Generator`` passed in, so
a run (and a resumed run) draws the same numbers on every device.
"""

from __future__ import annotations

import numpy as np
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
    """Warp pose maps, frames and the background plate and exemplars (when the sample has them) with the same
    [B, 2, 3] matrices (kornia): the plate stays the background of the warped frames.

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
    names = ["frame_prev", "frame_cur"] + [n for n in ("plate", "exemplar_prev", "exemplar_cur") if n in sample]
    frames = torch.cat([sample[n] for n in names], dim=1)  # [B, 6 to 15, S, S]
    frames = warp_affine(frames, m, (size, size), padding_mode="border", align_corners=True)
    for i, name in enumerate(names):
        out[name] = frames[:, 3 * i:3 * i + 3]
    out["frame_prev"] = torch.where(sample["has_prev"].to(m.device)[:, None, None, None], out["frame_prev"], 0.0)
    if "face" in sample:
        out["face"] = warp_affine(sample["face"], m, (size, size), padding_mode="zeros", align_corners=True)
    return out


# A person crop's margin beyond the joints' extent, as a share of their height (hair, dress and hands reach past
# the skeleton), and never under this many pixels.
CROP_MARGIN = 0.15
CROP_MARGIN_PX = 2
# The share of steps that still see the whole canvas: parts of it no window reaches (the letterbox's bars, the
# room's far side) are left to the plate only if the generator sees them; without, it painted smears there.
WHOLE_CANVAS_SHARE = 0.2
# The shortest side of a person crop (and at least half the canvas): the discriminator's five layers need 64.
MIN_CROP = 64


def person_window(points: np.ndarray, size: int, multiple: int, generator: torch.Generator
                  ) -> tuple[int, int, int, int] | None:  # fmt: skip
    """A random window ``(x0, y0, width, height)`` of an ``size``² canvas that holds every finite point of
    ``points`` [N, 2] (canvas pixels, NaN where missing) and a margin (:data:`CROP_MARGIN` of their height),
    each side a multiple of ``multiple``, at least half the canvas and :data:`MIN_CROP`; None without a finite
    point. Two numbers are drawn from ``generator`` either way, so that every process of a run stays in step."""
    u = torch.rand(2, generator=generator).tolist()
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    pts = pts[np.isfinite(pts).all(axis=1)]
    if len(pts) == 0:
        return None
    (x_lo, y_lo), (x_hi, y_hi) = pts.min(axis=0), pts.max(axis=0) + 1.0
    margin = max(CROP_MARGIN_PX, CROP_MARGIN * (y_hi - y_lo))
    start = []
    extent = []
    for (lo, hi), draw in zip(((x_lo - margin, x_hi + margin), (y_lo - margin, y_hi + margin)), u):
        lo, hi = max(0.0, lo), min(float(size), hi)
        side = min(size, max(size // 2, MIN_CROP, multiple * -(-round(max(hi - lo, 0.0)) // multiple)))
        first, last = max(0.0, hi - side), min(float(size - side), lo)  # starts that keep [lo, hi] inside
        if first > last:
            first = last = min(max(0.0, (lo + hi - side) / 2), float(size - side))
        start.append(round(first + draw * (last - first)))
        extent.append(side)
    return start[0], start[1], extent[0], extent[1]


def warped_points(points: np.ndarray, matrices: Tensor) -> np.ndarray:
    """[B, N, 2] canvas points moved by the [B, 2, 3] warps of :func:`warp_batch` (NaN stays NaN)."""
    m = matrices.detach().cpu().numpy().astype(np.float64)  # [B, 2, 3]
    return np.einsum("bij,bnj->bni", m[:, :, :2], points) + m[:, None, :, 2]


def crop(sample: dict[str, Tensor], window: tuple[int, int, int, int] | None) -> dict[str, Tensor]:
    """Every [B, C, S, S] tensor of ``sample`` cut to ``window`` ``(x0, y0, width, height)`` (None: as it is)."""
    if window is None:
        return sample
    x0, y0, w, h = window
    return {k: v[..., y0:y0 + h, x0:x0 + w] if v.dim() == 4 else v for k, v in sample.items()}


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
