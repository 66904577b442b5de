"""Reconstruction losses of the generator beyond pix2pix's plain L1: more weight on the person, and terms that
keep texture (SSIM, a Laplacian pyramid) where a per-pixel L1 settles for the average of what it has seen.

Images are ``[B, 3, S, S]`` in [-1, 1]; weight maps ``[B, 1, S, S]``.
"""

from __future__ import annotations

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
        face: [B, 1, S, S] the face's disc (:func:`clone.model.face.face_mask`, warped), or None.
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


# The face crop the face discriminator judges: this many face-disc radii either side of the centre.
FACE_CROP_RADII = 3.0
