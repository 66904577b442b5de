"""Reconstruction losses of the generator beyond pix2pix's plain L1: more weight on the person, and terms that
keep texture (SSIM, a Laplacian pyramid) where a per-pixel L1 settles for the average of what it has seen.

Images are ``[B, 3, S, S]`` in [-1, 1]; weight maps ``[B, 1, S, S]``.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F
from torch import Tensor

# A pixel belongs to the person where the real frame differs from the background plate by more than this
# ([-1, 1] units: 0.1 is 13 of 255 levels, above the noise of a compressed video's static background).
PERSON_THRESHOLD = 0.1
# ...grown by this many pixels per 256 of canvas, so that edges, hair and the pose's own area count as person.
PERSON_GROW = 4
SSIM_WINDOW = 11


def person_weights(real: Tensor, plate: Tensor | None, pose: Tensor, extra: float, face: Tensor | None = None,
                   face_extra: float = 0.0) -> Tensor:
    """Per-pixel loss weights: 1 on the background, ``1 + extra`` on the person, ``face_extra`` more on the face.

    The person is where the real frame is not the plate, or where its pose map is drawn, grown a little; without
    a plate, the pose map alone.

    Args:
        real: [B, 3, S, S] the real frames.
        plate: [B, 3, S, S] their (warped) background plates, or None.
        pose: [B, 3, S, S] their pose maps (-1 where nothing is drawn).
        extra: the person's extra weight (0: all ones).
        face: [B, 1, S, S] the face's disc (:func:`clone.train_ref.data.face_mask`, warped), or None.
        face_extra: the face's extra weight on top of the person's.

    Returns:
        [B, 1, S, S] weights.
    """
    drawn = (pose > -1.0 + 1e-3).any(dim=1, keepdim=True)  # [B, 1, S, S]
    if plate is not None:
        drawn = drawn | ((real - plate).abs().amax(dim=1, keepdim=True) > PERSON_THRESHOLD)
    grow = max(1, round(PERSON_GROW * real.shape[-1] / 256))
    mask = F.max_pool2d(drawn.float(), 2 * grow + 1, stride=1, padding=grow)  # [B, 1, S, S]
    weights = 1.0 + extra * mask
    if face is not None and face_extra:
        weights = weights + face_extra * face
    return weights


def weighted_l1(fake: Tensor, real: Tensor, weights: Tensor) -> Tensor:
    """Mean of ``weights * |fake - real|`` (weights broadcast over the channels)."""
    return (weights * (fake - real).abs()).mean()


def ssim_loss(fake: Tensor, real: Tensor, weights: Tensor) -> Tensor:
    """Weighted mean of ``1 - SSIM`` (11x11 Gaussian window) over pixels and channels."""
    import kornia

    # On [0, 1]: SSIM's luminance term assumes intensities >= 0 (around 0 it would turn any shift into a loss of 1).
    ssim = kornia.metrics.ssim((fake + 1.0) / 2.0, (real + 1.0) / 2.0, SSIM_WINDOW, max_val=1.0)  # [B, 3, S, S]
    return (weights * (1.0 - ssim)).mean() / weights.mean()


def laplacian_loss(fake: Tensor, real: Tensor, weights: Tensor, levels: int = 4) -> Tensor:
    """L1 between the band-pass levels of both images' Laplacian pyramids, each level's weight map pooled to its
    size and every band weighted alike, so that the fine bands, which a plain L1 hardly sees, count as much as
    the coarse. The low-pass residual is left out: the L1 term has the image's low frequencies."""
    from kornia.geometry.transform import build_laplacian_pyramid

    levels = max(2, min(levels, fake.shape[-1].bit_length() - 3))  # the coarsest band >= 4 pixels across
    fakes = build_laplacian_pyramid(fake, levels)[:-1]
    reals = build_laplacian_pyramid(real, levels)[:-1]
    total = fake.new_zeros(())
    for f, r in zip(fakes, reals):
        w = F.adaptive_avg_pool2d(weights, f.shape[-2:])  # [B, 1, s, s]
        total = total + (w * (f - r).abs()).mean()
    return total / len(fakes)


# The face crop the face discriminator judges: this many pixels square, this many face-disc radii across.
FACE_CROP = 64
FACE_CROP_RADII = 3.0


def face_boxes(face: Tensor) -> tuple[Tensor, Tensor]:
    """Square boxes around each sample's face disc, for :func:`kornia.geometry.transform.crop_and_resize`.

    Args:
        face: [B, 1, S, S] face discs (:func:`clone.train_ref.data.face_mask`, warped).

    Returns:
        ``(boxes [B, 4, 2] corner points (x, y) clockwise from top-left, present [B] bool)``; a sample without a
        face gets a box over the whole canvas and ``present`` False.
    """
    _, _, h, w = face.shape
    mass = face.flatten(1).sum(dim=1)  # [B]
    present = mass > 4.0
    ys = torch.arange(h, dtype=face.dtype, device=face.device)[None, :, None]
    xs = torch.arange(w, dtype=face.dtype, device=face.device)[None, None, :]
    m = face[:, 0]
    safe = mass.clamp(min=1.0)
    cx = (m * xs).flatten(1).sum(1) / safe
    cy = (m * ys).flatten(1).sum(1) / safe
    radius = (mass.clamp(min=1.0) / torch.pi).sqrt()
    half = FACE_CROP_RADII * radius
    cx = torch.where(present, cx, torch.full_like(cx, (w - 1) / 2))
    cy = torch.where(present, cy, torch.full_like(cy, (h - 1) / 2))
    half = torch.where(present, half, torch.full_like(half, max(h, w) / 2))
    x0, x1, y0, y1 = cx - half, cx + half, cy - half, cy + half
    boxes = torch.stack([torch.stack([x0, y0], -1), torch.stack([x1, y0], -1), torch.stack([x1, y1], -1),
                         torch.stack([x0, y1], -1)], dim=1)  # [B, 4, 2]
    return boxes, present


def face_crops(images: Tensor, boxes: Tensor) -> Tensor:
    """[B, C, FACE_CROP, FACE_CROP] crops of ``images`` [B, C, S, S] in ``boxes`` (bilinear, zeros outside)."""
    from kornia.geometry.transform import crop_and_resize

    return crop_and_resize(images, boxes, (FACE_CROP, FACE_CROP), align_corners=True)
