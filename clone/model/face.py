"""The face: where it is on the canvas, square crops around it, and the face pass that sharpens it.

The face is the disc around the mean of the visible face points (nose, eyes, ears, mouth corners) whose radius
is a twelfth of the reference's standing height. Training finds it in each (warped) sample's disc
(:func:`face_boxes`); driving, from the driven pose's points and the radius stored in the model
(:func:`boxes_around`): the same square either way.

The face pass, as in Everybody Dance Now: a small U-Net (:func:`face_pass_config`) sees the pose map and the
generated frame cropped around the face (``FACE_CROP`` pixels square, ``FACE_PASS_RADII`` radii either side of
the centre) and gives a residual, added inside a soft disc (:func:`blend_mask`) and pasted back onto the frame
(:func:`paste`). It trains in the same run as the generator, on the generator's frames without letting its
gradient into them (:class:`clone.train_ref.trainer.Trainer`), so the body is trained exactly as without it.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import torch
import torch.nn.functional as F
from torch import Tensor

from clone.model.networks import FRAME_CHANNELS, POSE_CHANNELS, GeneratorConfig, UNetGenerator, _last_conv

FACE_POINTS = ("nose", "r_eye", "l_eye", "r_ear", "l_ear", "mouth_right", "mouth_left")
# Crops are this many pixels square.
FACE_CROP = 64
# The face pass's crop: this many face radii either side of the face's centre (hair, chin and the neck's top).
FACE_PASS_RADII = 2.0
# Its residual counts fully within this many radii of the centre, falling to 0 at the next (inside the crop).
BLEND_INNER_RADII, BLEND_OUTER_RADII = 1.4, 1.9


def standing_height(joints: np.ndarray, layout: Any) -> float | None:
    """The body's standing height in pixels from a track's body15 joints ([T, J, 2] in ``layout``), or None when
    the track gives none."""
    from pose_io.errors import InputError
    from pose_io.layouts import BODY15
    from pose_io.measures import skeleton_height

    body = joints[:, : len(BODY15.joints)] if layout.name != "body15" else joints
    try:
        height = skeleton_height(body, "body15")
    except InputError:
        return None
    return float(height) if np.isfinite(height) and height > 0 else None


def face_radius(joints: np.ndarray, layout: Any) -> float | None:
    """Radius of the face's disc in canvas pixels (a twelfth of the body's standing height), or None when the
    layout has no face points or the track gives no height.

    Args:
        joints: [T, J, 2] canvas pixels in ``layout``.
        layout: their :class:`pose_io.layouts.JointLayout`.
    """
    if not any(layout.has(n) for n in FACE_POINTS[1:]):
        return None
    height = standing_height(joints, layout)
    return None if height is None else max(3.0, height / 12.0)


def face_centres(joints: np.ndarray, layout: Any) -> np.ndarray:
    """[T, 2] the mean of each frame's visible face points (canvas pixels), NaN where none is visible.

    Args:
        joints: [T, J, 2] canvas pixels in ``layout`` (NaN where missing).
        layout: their :class:`pose_io.layouts.JointLayout`.
    """
    idx = [layout.index(n) for n in FACE_POINTS if layout.has(n)]
    if not idx:
        return np.full((len(joints), 2), np.nan, dtype=np.float32)
    points = joints[:, idx].astype(np.float64)  # [T, F, 2]
    seen = np.isfinite(points).all(axis=-1)  # [T, F]
    count = seen.sum(axis=1)  # [T]
    total = np.where(seen[..., None], points, 0.0).sum(axis=1)  # [T, 2]
    with np.errstate(invalid="ignore", divide="ignore"):
        centres = total / count[:, None]
    centres[count == 0] = np.nan
    return centres.astype(np.float32)


def face_mask(joints: np.ndarray, layout: Any, radius: float, size: int) -> np.ndarray:
    """[S, S] bool: a disc of ``radius`` around the mean of the frame's visible face points (none visible: empty).

    Args:
        joints: [J, 2] one frame's canvas pixels in ``layout``.
    """
    import cv2

    mask = np.zeros((size, size), dtype=np.uint8)
    cx, cy = face_centres(joints[None], layout)[0]
    if np.isfinite(cx) and -radius < cx < size + radius and -radius < cy < size + radius:
        cv2.circle(mask, (round(float(cx)), round(float(cy))), round(radius), 1, -1)
    return mask.astype(bool)


@functools.lru_cache(maxsize=64)
def drawn_radius(radius: float) -> float:
    """The radius training sees of a face disc of ``radius``: :func:`face_boxes` takes it from the area of the disc
    :func:`face_mask` draws in whole pixels (``sqrt(area / pi)``), which differs from ``radius`` by up to a few per
    cent; driving crops with it, so that the face pass sees faces at the scale it was trained on."""
    import cv2

    r = round(radius)
    mask = np.zeros((2 * r + 3, 2 * r + 3), dtype=np.uint8)
    cv2.circle(mask, (r + 1, r + 1), r, 1, -1)
    return math.sqrt(float(mask.sum()) / math.pi)


def boxes_around(cx: Tensor, cy: Tensor, half: Tensor) -> Tensor:
    """[B, 4, 2] square boxes (corner points (x, y) clockwise from the top-left, kornia's order) of half-side
    ``half`` around ``(cx, cy)``, all [B]."""
    x0, x1, y0, y1 = cx - half, cx + half, cy - half, cy + half
    return torch.stack([torch.stack([x0, y0], -1), torch.stack([x1, y0], -1), torch.stack([x1, y1], -1),
                        torch.stack([x0, y1], -1)], dim=1)


def face_boxes(face: Tensor, radii: float) -> tuple[Tensor, Tensor]:
    """Square boxes ``radii`` face radii either side of each sample's face disc, for :func:`face_crops`.

    Args:
        face: [B, 1, S, S] face discs (:func:`face_mask`, warped with the sample).
        radii: half the box's side in radii of the disc.

    Returns:
        ``(boxes [B, 4, 2], present [B] bool)``; a sample without a face gets a box over the whole canvas and
        ``present`` False.
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
    half = radii * (safe / math.pi).sqrt()
    cx = torch.where(present, cx, torch.full_like(cx, (w - 1) / 2))
    cy = torch.where(present, cy, torch.full_like(cy, (h - 1) / 2))
    half = torch.where(present, half, torch.full_like(half, max(h, w) / 2))
    return boxes_around(cx, cy, half), present


def _axis(low: Tensor, high: Tensor, count: int, size: int) -> Tensor:
    """[B, count] grid_sample coordinates (align_corners=True) of ``count`` points from ``low`` to ``high``
    (pixels, [B]) along an axis of ``size`` pixels."""
    steps = torch.linspace(0.0, 1.0, count, device=low.device, dtype=low.dtype)  # [count]
    pixels = low[:, None] + (high - low)[:, None] * steps[None]  # [B, count]
    return 2.0 * pixels / max(size - 1, 1) - 1.0


def face_crops(images: Tensor, boxes: Tensor) -> Tensor:
    """[B, C, FACE_CROP, FACE_CROP] crops of ``images`` [B, C, S, S] in ``boxes`` [B, 4, 2] (axis-aligned, as
    :func:`boxes_around` makes them; corners on pixel centres, bilinear, zeros outside the image)."""
    h, w = images.shape[-2:]
    boxes = boxes.to(images.dtype)
    xs = _axis(boxes[:, 0, 0], boxes[:, 2, 0], FACE_CROP, w)  # [B, n]
    ys = _axis(boxes[:, 0, 1], boxes[:, 2, 1], FACE_CROP, h)
    grid = torch.stack(torch.broadcast_tensors(xs[:, None, :], ys[:, :, None]), dim=-1)  # [B, n, n, 2] (x, y)
    return F.grid_sample(images, grid, mode="bilinear", padding_mode="zeros", align_corners=True)


def blend_mask(device: torch.device | str = "cpu") -> Tensor:
    """[1, 1, FACE_CROP, FACE_CROP] where the face pass's residual counts: 1 within ``BLEND_INNER_RADII`` of the
    crop's centre, a cosine fall to 0 at ``BLEND_OUTER_RADII``."""
    n = FACE_CROP
    pixels_per_radius = (n - 1) / (2 * FACE_PASS_RADII)
    r = torch.arange(n, dtype=torch.float32, device=device) - (n - 1) / 2
    dist = torch.sqrt(r[:, None] ** 2 + r[None, :] ** 2) / pixels_per_radius  # [n, n] in radii
    t = ((dist - BLEND_INNER_RADII) / (BLEND_OUTER_RADII - BLEND_INNER_RADII)).clamp(0.0, 1.0)
    return (0.5 * (1.0 + torch.cos(math.pi * t)))[None, None]


def face_pass_config() -> GeneratorConfig:
    """The face pass's U-Net: pose map and generated frame cropped (6 channels) to an RGB residual, a 4x4
    bottleneck at ``FACE_CROP``²."""
    return GeneratorConfig(in_channels=POSE_CHANNELS + FRAME_CHANNELS, out_channels=FRAME_CHANNELS, base_channels=32,
                           depth=int(math.log2(FACE_CROP)) - 2, upsample="nearest")


def build_face_pass(config: GeneratorConfig | None = None) -> UNetGenerator:
    """A new face pass whose residual starts at zero (its last convolution zeroed): before it learns anything it
    leaves the generator's frame as it is."""
    net = UNetGenerator(config or face_pass_config())
    last = _last_conv(net.head)
    with torch.no_grad():
        last.weight.zero_()
        if last.bias is not None:
            last.bias.zero_()
    return net


def refine_crops(net: Callable[[Tensor], Tensor], pose_crop: Tensor, frame_crop: Tensor, mask: Tensor) -> Tensor:
    """The face pass's crops: ``frame_crop + mask * residual``, all [B, 3, FACE_CROP, FACE_CROP] (mask [1, 1, ...])."""
    return frame_crop + mask * net(torch.cat([pose_crop, frame_crop], dim=1))


def paste(frame: Tensor, crop_delta: Tensor, boxes: Tensor) -> Tensor:
    """``frame`` [B, 3, S, S] with ``crop_delta`` [B, 3, FACE_CROP, FACE_CROP] (zero at the crop's edge) put
    back into ``boxes`` [B, 4, 2] (the inverse of :func:`face_crops`, bilinear) and added, clamped to [-1, 1]."""
    height, width = frame.shape[-2:]
    boxes = boxes.to(frame.dtype)
    # Only the boxes' bounding region of the canvas is sampled (a face box is a few % of the canvas).
    low = boxes.amin(dim=(0, 1)).floor()  # [2] (x, y)
    high = boxes.amax(dim=(0, 1)).ceil() + 1.0
    x0, y0 = int(low[0].clamp(0, width)), int(low[1].clamp(0, height))
    x1, y1 = int(high[0].clamp(0, width)), int(high[1].clamp(0, height))
    if x1 <= x0 or y1 <= y0:  # every box is off the canvas
        return frame.clamp(-1.0, 1.0)
    # each region pixel's place in its crop, in grid_sample's coordinates of the crop
    px = torch.arange(x0, x1, device=frame.device, dtype=frame.dtype)  # [w']
    py = torch.arange(y0, y1, device=frame.device, dtype=frame.dtype)  # [h']
    bx0, bx1, by0, by1 = boxes[:, 0, 0], boxes[:, 2, 0], boxes[:, 0, 1], boxes[:, 2, 1]  # [B]
    u = 2.0 * (px[None] - bx0[:, None]) / (bx1 - bx0).clamp(min=1e-6)[:, None] - 1.0  # [B, w']
    v = 2.0 * (py[None] - by0[:, None]) / (by1 - by0).clamp(min=1e-6)[:, None] - 1.0  # [B, h']
    grid = torch.stack(torch.broadcast_tensors(u[:, None, :], v[:, :, None]), dim=-1)  # [B, h', w', 2]
    delta = F.grid_sample(crop_delta, grid, mode="bilinear", padding_mode="zeros", align_corners=True)
    out = frame.clone()
    out[..., y0:y1, x0:x1] += delta
    return out.clamp(-1.0, 1.0)


@dataclass(frozen=True, eq=False)
class FacePass:
    """A trained face pass, ready to drive: its network and the reference's face radius on the canvas.

    Attributes:
        net: the U-Net (eval mode), or its export on another runtime (:class:`clone.runtime.onnx.OnnxGenerator`).
        radius: the face's radius in canvas pixels (:func:`face_radius` of the reference).
    """

    net: Callable[[Tensor], Tensor]
    radius: float

    def __call__(self, frame: Tensor, pose: Tensor, centres: Tensor) -> Tensor:
        """``frame`` [B, 3, S, S] with its faces refined; ``pose`` the pose maps it was made from, ``centres``
        [B, 2] the face centres in canvas pixels (NaN: no face, the frame is left as it is)."""
        seen = torch.isfinite(centres).all(dim=1)  # [B]
        if not bool(seen.any()):
            return frame
        at = torch.nan_to_num(centres[seen])
        boxes = boxes_around(at[:, 0], at[:, 1], torch.full_like(at[:, 0], FACE_PASS_RADII * drawn_radius(self.radius)))
        mask = blend_mask(frame.device)
        frame_crop = face_crops(frame[seen], boxes)
        refined = refine_crops(self.net, face_crops(pose[seen], boxes), frame_crop, mask)
        out = frame.clone()
        out[seen] = paste(frame[seen], refined - frame_crop, boxes)
        return out


__all__ = [
    "BLEND_INNER_RADII", "BLEND_OUTER_RADII", "FACE_CROP", "FACE_PASS_RADII", "FACE_POINTS", "FacePass",
    "blend_mask", "boxes_around", "build_face_pass", "drawn_radius", "face_boxes", "face_centres", "face_crops", "face_mask",
    "face_pass_config", "face_radius", "paste", "refine_crops", "standing_height",
]
