"""OpenPose-style skeleton drawing with OpenCV.

One function draws one frame; it is shared by previews, training pose maps and driving, so what the
generator sees while training is exactly what it sees while driving.
"""

from __future__ import annotations

import cv2
import numpy as np

from pose_io.layouts import JointLayout

# Coordinates are drawn with 4 fractional bits so sub-pixel motion shows as anti-aliased motion.
_SHIFT = 4
_SCALE = float(1 << _SHIFT)


def draw_pose(
    canvas: np.ndarray,
    joints: np.ndarray,
    layout: JointLayout,
    thickness: int | None = None,
    antialias: bool = True,
) -> np.ndarray:
    """Draw one pose onto ``canvas`` in place and return it.

    Args:
        canvas: [H, W, 3] uint8 RGB image.
        joints: [J, 2] pixel coordinates in ``canvas``'s frame, NaN where missing.
        layout: the joints' layout (limbs and colours).
        thickness: limb width in pixels; default scales with the canvas (4 px at 512²).
        antialias: anti-aliased lines (smoother pose maps) or plain 8-connected ones.

    Returns:
        ``canvas``.
    """
    h, w = canvas.shape[:2]
    if thickness is None:
        thickness = max(1, round(min(h, w) / 128))
    line_type = cv2.LINE_AA if antialias else cv2.LINE_8
    ok = np.isfinite(joints).all(axis=-1)
    # Clamp far-away points so OpenCV's fixed-point maths does not overflow; clipping does the rest.
    pts = np.round(np.clip(np.nan_to_num(joints), -4 * max(h, w), 5 * max(h, w)) * _SCALE).astype(np.int32)
    for a, b in layout.limb_indices:
        if ok[a] and ok[b]:
            cv2.line(canvas, tuple(pts[a]), tuple(pts[b]), layout.colors[b], thickness, line_type, _SHIFT)
    radius = round(max(1.0, thickness * 1.2) * _SCALE)
    for j in np.flatnonzero(ok):
        cv2.circle(canvas, tuple(pts[j]), radius, layout.colors[j], -1, line_type, _SHIFT)
    return canvas


def blank_canvas(width: int, height: int, color: tuple[int, int, int] = (0, 0, 0)) -> np.ndarray:
    """[H, W, 3] uint8 canvas filled with ``color``."""
    canvas = np.empty((height, width, 3), dtype=np.uint8)
    # Broadcasting whole rows is ~50x faster than broadcasting a 3-vector over [H, W, 3].
    canvas[:] = np.tile(np.asarray(color, dtype=np.uint8), (width, 1))
    return canvas
