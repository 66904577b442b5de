"""The generator's square canvas: where it sits in the reference's frame, and the mapping px <-> canvas px.

A canvas is chosen once from the reference's pose track and stored in the reference model: either a square
crop around the region the performer occupies over the whole video (with a margin for the head, hands and
feet that a skeleton does not reach), or the full frame letterboxed into a square. Both are the same
transform — a square ``side`` pixels wide at ``(x0, y0)`` of the image, resized to ``size`` pixels — so one
pair of functions maps points either way and one function cuts frames.

Coordinates put pixel centres on integers (OpenPose's convention). Cutting a frame is an integer crop with
black padding followed by ``cv2.resize``, whose pixel-centre mapping is ``c = (p - x0 + 0.5) * k - 0.5`` with
``k = size / side``; the point functions use exactly that, so a pose drawn on the canvas lines up with the
canvas frame.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import cv2
import numpy as np

from clone.choices import CanvasMode
from pose_io.draw import blank_canvas, draw_pose
from pose_io.errors import InputError
from pose_io.layouts import JointLayout

# Plain names: a Canvas keeps (and the model file stores) the name, never the enum member.
CANVAS_MODES = tuple(m.value for m in CanvasMode)


@dataclass(frozen=True)
class Canvas:
    """A square window of the reference's frame, resized to ``size`` x ``size``.

    Attributes:
        x0: left edge of the window in image pixels (may be negative: padding).
        y0: top edge of the window in image pixels (may be negative: padding).
        side: width = height of the window in image pixels.
        size: canvas width = height in pixels (what the generator sees).
        image_size: (width, height) of the reference's frames.
        mode: ``"crop"`` or ``"full"`` (letterboxed full frame), for the record.
    """

    x0: int
    y0: int
    side: int
    size: int
    image_size: tuple[int, int]
    mode: str = "crop"

    def __post_init__(self) -> None:
        if self.side < 1 or self.size < 1:
            raise ValueError(f"canvas side and size must be positive, got side={self.side} size={self.size}")
        if self.mode not in CANVAS_MODES:
            raise ValueError(f"unknown canvas mode {self.mode!r}; valid: {', '.join(CANVAS_MODES)}")
        object.__setattr__(self, "image_size", tuple(int(v) for v in self.image_size))

    @property
    def scale(self) -> float:
        """Canvas pixels per image pixel."""
        return self.size / self.side

    def to_dict(self) -> dict:
        d = asdict(self)
        d["image_size"] = list(self.image_size)
        return d

    @classmethod
    def from_dict(cls, d: dict) -> Canvas:
        return cls(
            x0=int(d["x0"]), y0=int(d["y0"]), side=int(d["side"]), size=int(d["size"]),
            image_size=tuple(d["image_size"]), mode=str(d.get("mode", "crop")),
        )


def image_to_canvas(points: np.ndarray, canvas: Canvas) -> np.ndarray:
    """Map image pixel coordinates to canvas pixel coordinates.

    Args:
        points: [..., 2] (x, y) in the reference's image pixels; NaN stays NaN.
        canvas: the canvas.

    Returns:
        [..., 2] float32 canvas pixel coordinates.
    """
    origin = np.array([canvas.x0, canvas.y0], dtype=np.float64)
    return ((np.asarray(points, dtype=np.float64) - origin + 0.5) * canvas.scale - 0.5).astype(np.float32)


def canvas_to_image(points: np.ndarray, canvas: Canvas) -> np.ndarray:
    """Inverse of :func:`image_to_canvas`.

    Args:
        points: [..., 2] canvas pixel coordinates.
        canvas: the canvas.

    Returns:
        [..., 2] float32 image pixel coordinates.
    """
    origin = np.array([canvas.x0, canvas.y0], dtype=np.float64)
    return ((np.asarray(points, dtype=np.float64) + 0.5) / canvas.scale - 0.5 + origin).astype(np.float32)


def full_frame_canvas(image_size: tuple[int, int], size: int) -> Canvas:
    """The whole frame letterboxed (centred, black bars) into a ``size``² canvas."""
    w, h = image_size
    side = max(w, h)
    return Canvas(x0=(w - side) // 2, y0=(h - side) // 2, side=side, size=size, image_size=(w, h), mode="full")


def crop_canvas(
    joints: np.ndarray, image_size: tuple[int, int], size: int, margin: float = 0.25, quantile: float = 0.005
) -> Canvas:
    """A square crop around everywhere the performer goes, with a margin; the full frame if that is smaller.

    The region is the box of all visible joints over the whole track (after dropping the outer ``quantile``
    of coordinates on each side, so a few wrong detections do not blow it up), widened on every side by
    ``margin`` times the performer's typical height (head top, hands and feet lie outside the skeleton),
    then made square around its centre and shifted to stay inside the frame where it fits.

    Args:
        joints: [T, J, 2] image pixel coordinates, NaN where missing.
        image_size: (width, height) of the frames.
        size: canvas size in pixels.
        margin: extra border as a fraction of the median per-frame skeleton height.
        quantile: fraction of coordinates ignored at each end of the box.

    Returns:
        The canvas. Raises InputError when no frame has a visible joint.
    """
    w, h = image_size
    pts = np.asarray(joints, dtype=np.float64).reshape(-1, 2)
    pts = pts[np.isfinite(pts).all(axis=1)]
    if len(pts) == 0:
        raise InputError("reference poses: no visible joints in any frame, cannot place the canvas")
    lo = np.quantile(pts, quantile, axis=0)
    hi = np.quantile(pts, 1.0 - quantile, axis=0)
    with np.errstate(all="ignore"):
        y = np.asarray(joints, dtype=np.float64)[..., 1]
        heights = np.nanmax(y, axis=1) - np.nanmin(y, axis=1)
    heights = heights[np.isfinite(heights)]
    height = float(np.median(heights)) if len(heights) else float(hi[1] - lo[1])
    pad = margin * max(height, 1.0)
    lo, hi = lo - pad, hi + pad
    side = math.ceil(max(hi[0] - lo[0], hi[1] - lo[1], 1.0))
    if side >= max(w, h):
        return full_frame_canvas((w, h), size)
    cx, cy = (lo + hi) / 2.0
    x0 = round(float(cx) - side / 2.0)
    y0 = round(float(cy) - side / 2.0)
    # Inside the frame where the square fits in that direction; centred on the frame where it does not.
    x0 = min(max(x0, 0), w - side) if side <= w else (w - side) // 2
    y0 = min(max(y0, 0), h - side) if side <= h else (h - side) // 2
    return Canvas(x0=x0, y0=y0, side=side, size=size, image_size=(w, h), mode="crop")


def choose_canvas(
    joints: np.ndarray, image_size: tuple[int, int], size: int, mode: str = "crop", margin: float = 0.25
) -> Canvas:
    """The canvas for a reference: ``crop`` around the performer or the ``full`` frame letterboxed."""
    if mode == "crop":
        return crop_canvas(joints, image_size, size, margin=margin)
    if mode == "full":
        return full_frame_canvas(image_size, size)
    raise ValueError(f"unknown canvas mode {mode!r}; valid: {', '.join(CANVAS_MODES)}")


def cut_frame(frame: np.ndarray, canvas: Canvas) -> np.ndarray:
    """The canvas's view of one frame.

    Args:
        frame: [H, W, 3] uint8 RGB frame of the reference's size.
        canvas: the canvas.

    Returns:
        [size, size, 3] uint8 RGB; outside the frame is black.
    """
    h, w = frame.shape[:2]
    if (w, h) != canvas.image_size:
        raise InputError(f"frame is {w}x{h}, the canvas was made for {canvas.image_size[0]}x{canvas.image_size[1]}")
    x0, y0, s = canvas.x0, canvas.y0, canvas.side
    left, top = max(0, -x0), max(0, -y0)
    right, bottom = max(0, x0 + s - w), max(0, y0 + s - h)
    window = frame[max(0, y0): min(h, y0 + s), max(0, x0): min(w, x0 + s)]
    if left or top or right or bottom:
        window = cv2.copyMakeBorder(window, top, bottom, left, right, cv2.BORDER_CONSTANT, value=(0, 0, 0))
    if s == canvas.size:
        return np.ascontiguousarray(window)
    interp = cv2.INTER_AREA if s > canvas.size else cv2.INTER_LINEAR
    return cv2.resize(window, (canvas.size, canvas.size), interpolation=interp)


def pose_thickness(size: int) -> int:
    """Limb width of pose maps on a ``size``² canvas (2 px at 128²): thick enough to survive augmentation."""
    return max(1, round(size / 64))


def render_pose_map(joints: np.ndarray, size: int, layout: JointLayout) -> np.ndarray:
    """The pose map the generator sees: the skeleton drawn on black (a body31 pose with its details,
    :mod:`clone.model.detail_map`). Shared by training and driving.

    Args:
        joints: [J, 2] canvas pixel coordinates, NaN where missing.
        size: canvas size.
        layout: joint layout of ``joints``.

    Returns:
        [size, size, 3] uint8 RGB.
    """
    if layout.name == "body31":
        from clone.model.detail_map import render_detail_map

        return render_detail_map(joints, blank_canvas(size, size), pose_thickness(size))
    return draw_pose(blank_canvas(size, size), joints, layout, thickness=pose_thickness(size))
