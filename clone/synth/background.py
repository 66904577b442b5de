"""The fixed background of a synthetic video: a wall with soft noise over a floor of boards."""

from __future__ import annotations

import math

import numpy as np

from clone.synth.appearance import Backdrop
from clone.synth.paint import rgb


def floor_line(camera_ty: float, scale: float, height: int, pitch_deg: float) -> float:
    """Image row where the backdrop's floor meets its wall.

    The cameras are weak-perspective, so the floor has no true horizon; the wall starts a fixed 0.1 of
    the canvas above the ground line, higher when the camera looks down (it sees more floor).

    Args:
        camera_ty: image row of the ground origin (the camera's vertical translation), pixels.
        scale: pixels per metre.
        height: canvas height in pixels.
        pitch_deg: camera elevation in degrees (+ = from above).
    """
    y = camera_ty - 0.1 * height - scale * 3.0 * math.sin(math.radians(pitch_deg))
    return float(np.clip(y, 0.2 * height, height - 1.0))


def _wall(width: int, height: int, backdrop: Backdrop, floor_y: float, rng: np.random.Generator) -> np.ndarray:
    """[H, W, 3] float32: the wall's vertical gradient with low-frequency blotches, over the whole canvas."""
    ys = np.arange(height, dtype=np.float32)[:, None, None]
    out = np.empty((height, width, 3), dtype=np.float32)
    wall_frac = np.clip(ys / max(floor_y, 1.0), 0.0, 1.0)
    out[:] = rgb(backdrop.wall_top) + (rgb(backdrop.wall_bottom) - rgb(backdrop.wall_top)) * wall_frac
    # Blotches: coarse noise, upsampled bilinearly.
    coarse = rng.normal(0.0, 1.0, (9, 9)).astype(np.float32)
    gy = np.linspace(0, 8, height, dtype=np.float32)
    gx = np.linspace(0, 8, width, dtype=np.float32)
    iy, ix = np.minimum(gy.astype(int), 7), np.minimum(gx.astype(int), 7)
    fy, fx = (gy - iy)[:, None], (gx - ix)[None, :]
    blot = (coarse[iy][:, ix] * (1 - fy) * (1 - fx) + coarse[iy + 1][:, ix] * fy * (1 - fx)
            + coarse[iy][:, ix + 1] * (1 - fy) * fx + coarse[iy + 1][:, ix + 1] * fy * fx)
    out += (4.0 * blot)[..., None]
    return out


def _floor(width: int, height: int, top: int, backdrop: Backdrop, floor_y: float,
           rng: np.random.Generator) -> np.ndarray:
    """[H - top, W, 3] float32 rows ``top:`` of the floor: boards converging to a point above the canvas.

    Lighter far away, darker near; each board has its own shade and a dark seam.
    """
    fy_rows = np.arange(top, height, dtype=np.float32)[:, None]
    near = (fy_rows - floor_y) / max(height - floor_y, 1.0)
    colour = rgb(backdrop.floor_far) + (rgb(backdrop.floor_near) - rgb(backdrop.floor_far)) * near[..., None]
    cx = width / 2.0
    spread = 0.55 + 0.45 * near  # boards widen towards the camera
    board = (np.arange(width, dtype=np.float32)[None, :] - cx) / (spread * backdrop.board_width * width)
    index = np.floor(board).astype(np.int64)
    shade = rng.uniform(-9.0, 9.0, 256).astype(np.float32)[np.remainder(index, 256)]
    seam = np.abs(board - np.round(board)) * spread * backdrop.board_width * width < 0.6
    return colour + shade[..., None] - 22.0 * seam[..., None]


def make_background(width: int, height: int, backdrop: Backdrop, floor_y: float) -> np.ndarray:
    """The fixed background of a video: a wall with soft noise over a floor of boards.

    Args:
        width, height: canvas size in pixels.
        backdrop: colours and texture seed.
        floor_y: image row where the floor meets the wall.

    Returns:
        [H, W, 3] uint8 RGB.
    """
    # One generator, drawn in a fixed order (wall, floor, grain), so a backdrop always looks the same.
    rng = np.random.default_rng([int(backdrop.texture_seed) & 0xFFFFFFFF, 0xBAC])
    out = _wall(width, height, backdrop, floor_y, rng)
    top = int(np.clip(np.ceil(floor_y), 0, height))
    if top < height:
        out[top:] = _floor(width, height, top, backdrop, floor_y, rng)
        out[top:top + 2] *= 0.8  # skirting line
    out += rng.normal(0.0, 2.0, out.shape[:2]).astype(np.float32)[..., None]
    return np.clip(np.rint(out), 0, 255).astype(np.uint8)
