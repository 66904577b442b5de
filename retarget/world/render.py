"""A synthetic performer: projected 3D joints plus a :class:`~retarget.world.appearance.Look` -> RGB frames.

The body is built from a handful of analytic primitives around the joints, rasterised with numpy inside
each primitive's bounding box, with a per-pixel depth test (so a near limb hides a far one) and Lambert
shading from a pseudo-normal:

- limbs (upper/lower arm, thigh, shin), neck, hands, feet: tapered capsules; the normal at a pixel
  comes from its distance to the capsule's axis (a round cross-section);
- torso (and skirt): an elliptic cylinder between the shoulders and the hips whose cross-section turns
  with the shoulder and hip lines in 3D, so it is wide from the front and narrow from the side;
- head: a slightly tall ellipsoid with hair on top and at the back and skin, eyes and mouth at the
  front, decided from where the nose is, so the frame shows which way the person faces.

Clothes follow the body: shirt on the torso and sleeves, trousers/shorts/skirt on the legs, shoes, a
belt, and stripes or checks laid out in texture coordinates along each limb's axis and around it, so
the pattern moves with the body. A V-neck on the front of the shirt tells front from back.

Coordinates: ``xy`` in pixels (x right, y down, pixel centres at integers), ``depth`` in metres, larger
is farther; ``px_per_m`` converts metres across the image to pixels (a weak-perspective camera). The
per-frame work is a few dozen numpy operations per primitive on float32 buffers that are allocated
once per video, which keeps it well above 20 frames/s at 256² on one core.
"""

from __future__ import annotations

import dataclasses
import json
import logging
import math
import os
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from pose_io.atomic import atomic_dir, check_new_output
from pose_io.layouts import BODY25
from pose_io.track import PoseTrack
from pose_io.writers import write_track
from retarget.world.appearance import Backdrop, Look
from retarget.world.camera import (
    FRAME_GROUND,
    FRAME_SCALE,
    facing_angle,
    frame_camera,
    ground_origin,
    project,
)
from retarget.world.skeleton import WORLD_JOINTS, Motion3D, Skeleton, retarget_3d

logger = logging.getLogger(__name__)

# Direction towards the light in camera coordinates (x right, y down, z away): above, left, in front.
_LIGHT = np.array([-0.38, -0.72, -0.58], dtype=np.float64)
_LIGHT /= np.linalg.norm(_LIGHT)
_AMBIENT = 0.42
_DIFFUSE = 0.62
_EYE = np.array([34, 26, 24], dtype=np.float32)
_MOUTH = np.array([150, 72, 70], dtype=np.float32)

_PLAIN, _STRIPES, _CHECKS = 0, 1, 2
_PATTERN_CODES = {"plain": _PLAIN, "stripes": _STRIPES, "checks": _CHECKS}


@dataclass(frozen=True)
class Paint:
    """A cloth or skin colour with an optional pattern (``period`` metres along and around the body)."""

    base: np.ndarray  # [3] float32 RGB 0..255
    accent: np.ndarray  # [3] float32
    pattern: int = _PLAIN
    period: float = 1.0

    @staticmethod
    def solid(rgb: Sequence[int]) -> Paint:
        """One plain colour."""
        return Paint(_rgb(rgb), _rgb(rgb))

    def colours(self, u: np.ndarray, v: np.ndarray | None) -> np.ndarray:
        """[h, w, 3] (or broadcastable [1, 1, 3]) colours at texture coordinates ``u`` (along), ``v`` (around)."""
        if self.pattern == _PLAIN:
            return self.base[None, None]
        if self.pattern == _STRIPES or v is None:
            mask = np.remainder(u, self.period) < 0.4 * self.period
        else:
            mask = (np.floor(u * (2.0 / self.period)) + np.floor(v * (2.0 / self.period))) % 2 == 1
        return np.where(mask[..., None], self.accent, self.base)


Bands = tuple[tuple[float, Paint], ...]  # (t_end, paint) along a primitive's axis, the last one to t=1 and beyond


def _rgb(c: Sequence[int]) -> np.ndarray:
    return np.asarray(c, dtype=np.float32)


@dataclass(frozen=True)
class _Materials:
    """A look's paints, arranged per body part (built once per video)."""

    skin: Paint
    hair: Paint
    shirt: Paint
    bottom: Paint
    belt: Paint
    shoes: Paint
    upper_arm: Bands
    forearm: Bands
    thigh: Bands
    shin: Bands

    @staticmethod
    def of(look: Look) -> _Materials:
        skin = Paint.solid(look.skin)
        shirt = Paint(_rgb(look.top), _rgb(look.top_accent), _PATTERN_CODES[look.pattern], look.pattern_period)
        bottom = Paint.solid(look.bottom)
        upper_arm: Bands = {"long": ((1.0, shirt),), "short": ((0.55, shirt), (1.0, skin)),
                            "none": ((1.0, skin),)}[look.sleeves]
        forearm: Bands = ((0.96, shirt), (1.0, skin)) if look.sleeves == "long" else ((1.0, skin),)
        thigh: Bands = ((0.6, bottom), (1.0, skin)) if look.bottom_style == "shorts" else (
            ((1.0, bottom),) if look.bottom_style == "trousers" else ((1.0, skin),))
        shin: Bands = ((1.0, bottom),) if look.bottom_style == "trousers" else ((1.0, skin),)
        return _Materials(skin=skin, hair=Paint.solid(look.hair), shirt=shirt, bottom=bottom,
                          belt=Paint.solid(look.belt), shoes=Paint.solid(look.shoes),
                          upper_arm=upper_arm, forearm=forearm, thigh=thigh, shin=shin)


def make_background(width: int, height: int, backdrop: Backdrop, floor_y: float) -> np.ndarray:
    """The fixed background of a video: a wall with soft noise over a floor of boards.

    Args:
        width, height: canvas size in pixels.
        backdrop: colours and texture seed.
        floor_y: image row where the floor meets the wall.

    Returns:
        [H, W, 3] uint8 RGB.
    """
    rng = np.random.default_rng([int(backdrop.texture_seed) & 0xFFFFFFFF, 0xBAC])
    ys = np.arange(height, dtype=np.float32)[:, None, None]
    out = np.empty((height, width, 3), dtype=np.float32)
    wall_frac = np.clip(ys / max(floor_y, 1.0), 0.0, 1.0)
    out[:] = _rgb(backdrop.wall_top) + (_rgb(backdrop.wall_bottom) - _rgb(backdrop.wall_top)) * wall_frac
    # Low-frequency blotches on the wall: coarse noise, upsampled bilinearly.
    coarse = rng.normal(0.0, 1.0, (9, 9)).astype(np.float32)
    gy = np.linspace(0, 8, height, dtype=np.float32)
    gx = np.linspace(0, 8, width, dtype=np.float32)
    iy, ix = np.minimum(gy.astype(int), 7), np.minimum(gx.astype(int), 7)
    fy, fx = (gy - iy)[:, None], (gx - ix)[None, :]
    blot = (coarse[iy][:, ix] * (1 - fy) * (1 - fx) + coarse[iy + 1][:, ix] * fy * (1 - fx)
            + coarse[iy][:, ix + 1] * (1 - fy) * fx + coarse[iy + 1][:, ix + 1] * fy * fx)
    out += (4.0 * blot)[..., None]
    # Floor: boards converging to a vanishing point above the canvas, lighter far away, darker near.
    top = int(np.clip(np.ceil(floor_y), 0, height))
    if top < height:
        fy_rows = np.arange(top, height, dtype=np.float32)[:, None]
        near = (fy_rows - floor_y) / max(height - floor_y, 1.0)
        colour = _rgb(backdrop.floor_far) + (_rgb(backdrop.floor_near) - _rgb(backdrop.floor_far)) * near[..., None]
        cx = width / 2.0
        spread = 0.55 + 0.45 * near  # boards widen towards the camera
        board = (np.arange(width, dtype=np.float32)[None, :] - cx) / (spread * backdrop.board_width * width)
        index = np.floor(board).astype(np.int64)
        shade = rng.uniform(-9.0, 9.0, 256).astype(np.float32)[np.remainder(index, 256)]
        seam = np.abs(board - np.round(board)) * spread * backdrop.board_width * width < 0.6
        floor = colour + shade[..., None] - 22.0 * seam[..., None]
        out[top:] = floor
        out[top:top + 2] *= 0.8  # skirting line
    out += rng.normal(0.0, 2.0, out.shape[:2]).astype(np.float32)[..., None]
    return np.clip(np.rint(out), 0, 255).astype(np.uint8)


def _unit(v: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    n = float(np.linalg.norm(v))
    return v / n if n > 1e-9 else fallback


class Rasterizer:
    """Colour and depth buffers of one canvas plus the primitives drawn into them.

    Every primitive is rasterised inside its bounding box only, in float32, with an anti-aliased edge
    (coverage from the signed distance to the silhouette) and a depth test; the depth buffer takes a
    primitive's depth where it covers at least half a pixel.

    Args:
        background: [H, W, 3] uint8 RGB shown where nothing is drawn.
    """

    def __init__(self, background: np.ndarray) -> None:
        if background.ndim != 3 or background.shape[2] != 3 or background.dtype != np.uint8:
            raise ValueError(f"background must be [H, W, 3] uint8, got {background.shape} {background.dtype}")
        self.height, self.width = background.shape[:2]
        self._background = background.astype(np.float32)
        self.color = np.empty_like(self._background)  # [H, W, 3] float32, 0..255
        self.depth = np.empty((self.height, self.width), dtype=np.float32)  # metres, inf = empty
        self._xs = np.arange(self.width, dtype=np.float32)[None, :]
        self._ys = np.arange(self.height, dtype=np.float32)[:, None]
        self.clear()

    def clear(self) -> None:
        """Back to the bare background."""
        np.copyto(self.color, self._background)
        self.depth.fill(np.inf)

    def image(self, out: np.ndarray | None = None) -> np.ndarray:
        """The canvas as [H, W, 3] uint8 RGB (into ``out`` when given)."""
        if out is None:
            out = np.empty((self.height, self.width, 3), dtype=np.uint8)
        np.copyto(out, np.rint(self.color), casting="unsafe")
        return out

    def _window(self, lo: np.ndarray, hi: np.ndarray) -> tuple[int, int, int, int] | None:
        """Clipped integer pixel box [y0:y1, x0:x1] around the float box ``lo``..``hi`` (x, y), or None."""
        x0 = max(math.floor(lo[0]) - 1, 0)
        y0 = max(math.floor(lo[1]) - 1, 0)
        x1 = min(math.ceil(hi[0]) + 2, self.width)
        y1 = min(math.ceil(hi[1]) + 2, self.height)
        if x0 >= x1 or y0 >= y1:
            return None
        return y0, y1, x0, x1

    def _composite(self, box: tuple[int, int, int, int], cover: np.ndarray, z: np.ndarray, rgb: np.ndarray,
                   nx: np.ndarray, ny: np.ndarray, nz: np.ndarray) -> None:
        """Shade ``rgb`` with normal (nx, ny, nz) and blend it in where it is nearer than what is there.

        ``cover`` is the pixel coverage in [0, 1] (anti-aliased edge); the depth buffer takes the new
        depth only where the primitive covers at least half the pixel.
        """
        y0, y1, x0, x1 = box
        zbuf = self.depth[y0:y1, x0:x1]
        hit = (cover > 0) & (z < zbuf)
        if not hit.any():
            return
        shade = nx * np.float32(_LIGHT[0]) + ny * np.float32(_LIGHT[1]) + nz * np.float32(_LIGHT[2])
        np.maximum(shade, 0, out=shade)
        shade *= np.float32(_DIFFUSE)
        shade += np.float32(_AMBIENT)
        cbuf = self.color[y0:y1, x0:x1]
        new = rgb * shade[..., None]
        new -= cbuf
        new *= cover[..., None]
        new += cbuf
        np.copyto(cbuf, new, where=hit[..., None])
        np.copyto(zbuf, z, where=hit & (cover >= 0.5))

    def capsule(self, pa: np.ndarray, pb: np.ndarray, ra_m: float, rb_m: float, ppm: float, bands: Bands) -> None:
        """A tapered capsule from ``pa`` to ``pb`` ([3] metres, camera coordinates) with radii in metres."""
        a2, b2 = pa[:2] * ppm, pb[:2] * ppm
        ra, rb = ra_m * ppm, rb_m * ppm
        box = self._window(np.minimum(a2 - ra, b2 - rb), np.maximum(a2 + ra, b2 + rb))
        if box is None:
            return
        y0, y1, x0, x1 = box
        px = self._xs[:, x0:x1] - np.float32(a2[0])  # [1, w]
        py = self._ys[y0:y1] - np.float32(a2[1])  # [h, 1]
        dx, dy = float(b2[0] - a2[0]), float(b2[1] - a2[1])
        length2 = dx * dx + dy * dy
        if length2 > 1e-6:
            t = px * np.float32(dx / length2) + py * np.float32(dy / length2)  # [h, w]
            np.clip(t, 0.0, 1.0, out=t)
        else:
            t = np.zeros((y1 - y0, x1 - x0), dtype=np.float32)
        ox = px - t * np.float32(dx)
        oy = py - t * np.float32(dy)
        dist = np.sqrt(ox * ox + oy * oy)
        r = t * np.float32(rb - ra) + np.float32(ra)
        cover = r - dist
        cover += 0.5
        np.clip(cover, 0.0, 1.0, out=cover)
        inv_r = 1.0 / r
        nx = ox * inv_r
        ny = oy * inv_r
        s2 = np.minimum(nx * nx + ny * ny, 1.0)
        nz = -np.sqrt(1.0 - s2)  # towards the camera
        z = t * np.float32(pb[2] - pa[2]) + np.float32(pa[2])
        z += nz * r * np.float32(1.0 / ppm)
        # Texture: u along the axis in metres, v around it (arc length) in metres.
        u = t * np.float32(np.linalg.norm(pb - pa))
        v = None
        if any(p.pattern == _CHECKS for _, p in bands):
            if length2 > 1e-6:
                lateral = (oy * np.float32(dx) - ox * np.float32(dy)) * np.float32(1.0 / math.sqrt(length2))
            else:
                lateral = ox
            v = np.arcsin(np.clip(lateral * inv_r, -1.0, 1.0)) * (r * np.float32(1.0 / ppm))
        rgb = bands[-1][1].colours(u, v)
        for t_end, paint in reversed(bands[:-1]):
            rgb = np.where((t < t_end)[..., None], paint.colours(u, v), rgb)
        self._composite(box, cover, z, rgb, nx, ny, nz)

    def trunk(self, top: np.ndarray, bottom: np.ndarray, stations: Sequence[tuple[float, np.ndarray]],
               caps: tuple[float, float], ppm: float,
               paint: Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], np.ndarray]) -> None:
        """An elliptic cylinder along ``top`` -> ``bottom`` whose cross-section changes along the axis.

        Each station ``(t, M)`` gives the cross-section at axis fraction ``t`` as a 2x2 matrix mapping the
        unit circle to (image-lateral, depth) metres: columns are the two half axes. Between stations
        ``M`` is interpolated linearly. For a pixel at lateral offset x the visible (nearest) surface
        point, its normal and its angle on the ellipse follow in closed form.

        Args:
            top, bottom: [3] axis ends in metres (camera coordinates).
            stations: (t, [2, 2] M) sorted by t, covering 0 and 1.
            caps: how far (metres) the body continues, rounded, beyond the top and the bottom.
            paint: ``(t, u, phi, half) -> [h, w, 3]`` colours, with ``u`` metres along the axis from the
                top, ``phi`` the angle on the cross-section (pi/2 = front) and ``half`` (a, b) half axes.
        """
        a2, b2 = top[:2] * ppm, bottom[:2] * ppm
        axis = b2 - a2
        length_px = float(np.hypot(*axis))
        if length_px < 1e-3:
            return
        d = axis / length_px
        perp = np.array([-d[1], d[0]])  # image-lateral unit vector
        ts = np.array([s[0] for s in stations], dtype=np.float32)
        ms = np.stack([s[1] for s in stations]).astype(np.float32)  # [S, 2, 2]
        reach = float(np.max(np.sqrt((ms[:, 0] ** 2).sum(-1)))) * ppm  # largest half width in px
        cap0, cap1 = caps[0] * ppm / length_px, caps[1] * ppm / length_px  # caps as axis fractions
        lo = np.minimum(a2 - d * caps[0] * ppm, b2 + d * caps[1] * ppm) - reach
        hi = np.maximum(a2 - d * caps[0] * ppm, b2 + d * caps[1] * ppm) + reach
        box = self._window(lo, hi)
        if box is None:
            return
        y0, y1, x0, x1 = box
        px = self._xs[:, x0:x1] - np.float32(a2[0])
        py = self._ys[y0:y1] - np.float32(a2[1])
        t_raw = (px * np.float32(d[0]) + py * np.float32(d[1])) * np.float32(1.0 / length_px)  # [h, w]
        x = (px * np.float32(perp[0]) + py * np.float32(perp[1])) * np.float32(1.0 / ppm)  # lateral metres
        t = np.clip(t_raw, 0.0, 1.0)
        m00, m01, m10, m11 = (np.interp(t, ts, ms[:, r, c]).astype(np.float32)
                              for r, c in ((0, 0), (0, 1), (1, 0), (1, 1)))
        sxx = m00 * m00 + m01 * m01  # squared half width
        sxz = m00 * m10 + m01 * m11
        det = m00 * m11 - m01 * m10
        # Rounded ends: the half width shrinks like an ellipse past the top and the bottom.
        # Rounded ends: past the top the half width shrinks like a parabola (sloping shoulders), past the
        # bottom like an ellipse.
        over = np.where(t_raw < 0, -t_raw / np.float32(max(cap0, 1e-6)), (t_raw - 1) / np.float32(max(cap1, 1e-6)))
        np.clip(over, 0.0, 1.0, out=over)
        end = 1.0 - np.where(t_raw < 0, over, over * over)
        half_w = np.sqrt(sxx * end)
        cover = (half_w - np.abs(x)) * np.float32(ppm) + 0.5
        # Along the axis the body ends where the caps end (the lateral test alone leaves a 1 px line there).
        beyond = np.maximum(-t_raw - np.float32(cap0), t_raw - np.float32(1.0 + cap1)) * np.float32(length_px)
        np.minimum(cover, 0.5 - beyond, out=cover)
        np.clip(cover, 0.0, 1.0, out=cover)
        root = np.sqrt(np.maximum(sxx - x * x, 0.0))
        abs_det = np.maximum(np.abs(det), 1e-6)
        inv_sxx = 1.0 / np.maximum(sxx, 1e-8)
        zoff = (sxz * x - abs_det * root) * inv_sxx  # nearest surface point relative to the axis
        z = t_raw * np.float32(bottom[2] - top[2]) + np.float32(top[2]) + zoff
        # Angle on the ellipse: (cos, sin) = M^-1 (x, zoff); normal ~ M^-T (cos, sin).
        inv_det = 1.0 / np.where(det >= 0, np.maximum(det, 1e-6), np.minimum(det, -1e-6))
        c = (m11 * x - m01 * zoff) * inv_det
        s = (m00 * zoff - m10 * x) * inv_det
        n_lat = (m11 * c - m10 * s) * inv_det
        n_dep = (m00 * s - m01 * c) * inv_det
        # Past the ends the surface bends over the cap, like a dome.
        bend = np.sqrt(np.maximum(1.0 - end, 0.0)) * np.sign(t_raw - 0.5)
        norm = 1.0 / np.maximum(np.sqrt(n_lat * n_lat + n_dep * n_dep + bend * bend), 1e-6)
        flip = np.where(n_dep > 0, -norm, norm)  # the visible side faces the camera
        n_lat *= flip
        n_dep *= flip
        bend *= np.abs(flip)
        nx = n_lat * np.float32(perp[0]) + bend * np.float32(d[0])
        ny = n_lat * np.float32(perp[1]) + bend * np.float32(d[1])
        phi = np.arctan2(s, c)
        u = t_raw * np.float32(np.linalg.norm(bottom - top))
        rgb = paint(t_raw, u, phi, (np.sqrt(m00 * m00 + m10 * m10), np.sqrt(m01 * m01 + m11 * m11)))
        self._composite(box, cover, z, rgb, nx, ny, n_dep)

    def ellipsoid(self, pa: np.ndarray, pb: np.ndarray, r_m: float, ppm: float,
                        paint: Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]) -> None:
        """A short capsule (a slightly tall head) whose colour depends on the 3D surface normal."""
        a2, b2 = pa[:2] * ppm, pb[:2] * ppm
        r = r_m * ppm
        box = self._window(np.minimum(a2, b2) - r, np.maximum(a2, b2) + r)
        if box is None:
            return
        y0, y1, x0, x1 = box
        px = self._xs[:, x0:x1] - np.float32(a2[0])
        py = self._ys[y0:y1] - np.float32(a2[1])
        dx, dy = float(b2[0] - a2[0]), float(b2[1] - a2[1])
        length2 = dx * dx + dy * dy
        t = (px * np.float32(dx / length2) + py * np.float32(dy / length2)) if length2 > 1e-6 else px * 0 + py * 0
        np.clip(t, 0.0, 1.0, out=t)
        ox = px - t * np.float32(dx)
        oy = py - t * np.float32(dy)
        dist = np.sqrt(ox * ox + oy * oy)
        cover = np.clip(np.float32(r + 0.5) - dist, 0.0, 1.0)
        nx = ox * np.float32(1.0 / r)
        ny = oy * np.float32(1.0 / r)
        nz = -np.sqrt(np.maximum(1.0 - nx * nx - ny * ny, 0.0))
        # The axis' own depth tilt: along the axis the cap's normal leans with it.
        z = t * np.float32(pb[2] - pa[2]) + np.float32(pa[2]) + nz * np.float32(r_m)
        self._composite(box, cover, z, paint(nx, ny, nz), nx, ny, nz)


class PerformerRenderer:
    """Draws one performer over one fixed background, frame by frame, into reused buffers.

    Args:
        look: the performer's appearance.
        background: [H, W, 3] uint8 (see :func:`make_background`).
        joint_names: names of the joints in the arrays passed to :meth:`render`, in order; the body
            is built from the motion world's joints, so every name of ``WORLD_JOINTS`` must be there.
    """

    def __init__(self, look: Look, background: np.ndarray, joint_names: Sequence[str] = WORLD_JOINTS) -> None:
        index = {n: i for i, n in enumerate(joint_names)}
        lacking = [n for n in WORLD_JOINTS if n not in index]
        if lacking:
            raise ValueError(f"renderer needs joints {', '.join(lacking)}; got {', '.join(joint_names)}")
        self.look = look
        self._j: Mapping[str, int] = index
        self._mat = _Materials.of(look)
        self._ras = Rasterizer(background)
        self.width, self.height = self._ras.width, self._ras.height

    def render(self, xy: np.ndarray, depth: np.ndarray, px_per_m: float, out: np.ndarray | None = None
               ) -> np.ndarray:
        """One frame.

        Args:
            xy: [K, 2] pixel coordinates of the joints (order of ``joint_names``), NaN where missing.
            depth: [K] depth in metres, larger is farther.
            px_per_m: pixels per metre across the image.
            out: optional [H, W, 3] uint8 array to write into.

        Returns:
            [H, W, 3] uint8 RGB (``out`` when given).
        """
        self._ras.clear()
        ppm = float(px_per_m)
        xy = np.asarray(xy, dtype=np.float64)
        depth = np.asarray(depth, dtype=np.float64)
        # [K, 3] joints in metres in camera coordinates (x right, y down, z away).
        p3 = np.concatenate([xy / ppm, depth[:, None]], axis=1)
        # Far to near: with the depth test this order only matters for anti-aliased edges.
        for _, draw in sorted(self._parts(p3, ppm), key=lambda item: -item[0]):
            draw()
        return self._ras.image(out)

    def silhouette(self) -> np.ndarray:
        """[H, W] bool: pixels the body covers (at least half) in the last rendered frame."""
        return np.isfinite(self._ras.depth)

    def _parts(self, p3: np.ndarray, ppm: float) -> list[tuple[float, Callable[[], None]]]:
        """(mean depth, draw callable) for every body part whose joints are all present."""
        j, shape, mat, look = self._j, self.look.shape, self._mat, self.look
        parts: list[tuple[float, Callable[[], None]]] = []

        def ok(*names: str) -> bool:
            return all(np.isfinite(p3[j[n]]).all() for n in names)

        def capsule(a: str | np.ndarray, b: str | np.ndarray, ra: float, rb: float, bands: Bands) -> None:
            pa = p3[j[a]] if isinstance(a, str) else a
            pb = p3[j[b]] if isinstance(b, str) else b
            parts.append((0.5 * (pa[2] + pb[2]),
                          lambda: self._ras.capsule(pa, pb, ra, rb, ppm, bands)))

        up = np.array([0.0, -1.0, 0.0])
        for side in ("l", "r"):
            sh, el, wr = f"{side}_shoulder", f"{side}_elbow", f"{side}_wrist"
            hip, kn, an, toe = f"{side}_hip", f"{side}_knee", f"{side}_ankle", f"{side}_big_toe"
            if ok(sh, el):
                capsule(sh, el, *shape.upper_arm, mat.upper_arm)
            if ok(el, wr):
                capsule(el, wr, *shape.forearm, mat.forearm)
                direction = _unit(p3[j[wr]] - p3[j[el]], up)
                tip = p3[j[wr]] + direction * shape.hand_length
                capsule(p3[j[wr]] + direction * 0.01, tip, shape.hand_radius, shape.hand_radius * 0.8,
                        ((1.0, mat.skin),))
            if ok(hip, kn):
                # Start a little down the thigh so its round top does not bulge out of the pelvis.
                capsule(p3[j[hip]] + 0.12 * (p3[j[kn]] - p3[j[hip]]), kn, *shape.thigh, mat.thigh)
            if ok(kn, an):
                capsule(kn, an, *shape.shin, mat.shin)
            if ok(an, toe):
                direction = _unit(p3[j[toe]] - p3[j[an]], -up)
                heel = p3[j[an]] - direction * shape.heel
                capsule(heel, toe, shape.foot_radius * 1.1, shape.foot_radius * 0.8, ((1.0, mat.shoes),))
        if ok("neck", "head"):
            capsule("neck", "head", shape.neck_radius, shape.neck_radius * 0.9, ((1.0, mat.skin),))
        if ok("l_shoulder", "r_shoulder", "l_hip", "r_hip"):
            forward = self._forward(p3, up)
            parts.append(self._torso(p3, ppm, forward))
            if look.bottom_style == "skirt" and ok("l_knee", "r_knee"):
                parts.append(self._skirt(p3, ppm, forward))
        if ok("head", "neck"):
            parts.extend(self._head(p3, ppm, up))
        return parts

    def _forward(self, p3: np.ndarray, up: np.ndarray) -> np.ndarray:
        """[3] unit vector the chest faces, from the shoulder line and the spine, signed by the nose."""
        j = self._j
        left = p3[j["l_shoulder"]] - p3[j["r_shoulder"]] + p3[j["l_hip"]] - p3[j["r_hip"]]
        spine = _unit(0.5 * (p3[j["l_shoulder"]] + p3[j["r_shoulder"]] - p3[j["l_hip"]] - p3[j["r_hip"]]), up)
        forward = _unit(np.cross(left, spine), np.array([0.0, 0.0, -1.0]))
        nose_dir = p3[j["nose"]] - p3[j["neck"]]
        if np.isfinite(nose_dir).all() and float(np.dot(forward, nose_dir)) < 0:
            forward = -forward
        return forward

    @staticmethod
    def _section(half_a: float, lateral: np.ndarray, half_b: float, forward: np.ndarray, perp: np.ndarray
                 ) -> np.ndarray:
        """[2, 2] cross-section matrix: columns = half axes (lateral, forward) in (image-lateral, depth) metres."""
        e1 = np.array([np.dot(lateral[:2], perp), lateral[2]])
        e2 = np.array([np.dot(forward[:2], perp), forward[2]])
        return np.stack([half_a * e1, half_b * e2], axis=1)

    def _torso(self, p3: np.ndarray, ppm: float, forward: np.ndarray
               ) -> tuple[float, Callable[[], None]]:
        j, shape, mat = self._j, self.look.shape, self._mat
        ls, rs, lh, rh = (p3[j[n]] for n in ("l_shoulder", "r_shoulder", "l_hip", "r_hip"))
        top, bottom = 0.5 * (ls + rs), 0.5 * (lh + rh)
        spine2 = _unit(bottom[:2] - top[:2], np.array([0.0, 1.0]))
        perp = np.array([-spine2[1], spine2[0]])
        lat_s = _unit(ls - rs, np.array([1.0, 0.0, 0.0]))
        lat_h = _unit(lh - rh, lat_s)
        # Make the lateral axes perpendicular to the forward direction so the section is a true ellipse.
        lat_s = _unit(lat_s - forward * np.dot(lat_s, forward), lat_s)
        lat_h = _unit(lat_h - forward * np.dot(lat_h, forward), lat_h)
        lat_w = _unit(lat_s + lat_h, lat_s)
        a_s = 0.5 * float(np.linalg.norm(ls - rs)) + shape.shoulder_pad
        a_h = 0.5 * float(np.linalg.norm(lh - rh)) + shape.hip_pad
        stations = (
            (0.0, self._section(a_s, lat_s, shape.chest_depth * 0.85, forward, perp)),
            (0.22, self._section(a_s * 0.97, lat_s, shape.chest_depth, forward, perp)),
            (0.62, self._section(shape.waist * 0.5 * (a_s + a_h), lat_w, 0.5 * (shape.chest_depth + shape.hip_depth),
                                 forward, perp)),
            (1.0, self._section(a_h, lat_h, shape.hip_depth, forward, perp)),
        )
        shirt, belt, bottom_paint, skin = mat.shirt, mat.belt, mat.bottom, mat.skin
        skirt = self.look.bottom_style == "skirt"

        def paint(t: np.ndarray, u: np.ndarray, phi: np.ndarray, half: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
            around = phi * (0.5 * (half[0] + half[1]))  # arc length, metres
            rgb = np.where((t < 0.76)[..., None], shirt.colours(u, around),
                           np.where((t < 0.82)[..., None], belt.base, (belt if skirt else bottom_paint).base))
            # A V-neck on the front only: from the top of the chest down to a point.
            front = np.abs(phi - np.float32(np.pi / 2)) * half[0]
            vneck = (front < 0.035 - 0.55 * np.maximum(u, 0.0)) & (phi > 0)
            return np.where(vneck[..., None], skin.base, rgb)

        return (0.5 * (top[2] + bottom[2]),
                lambda: self._ras.trunk(top, bottom, stations, (0.09, 0.06), ppm, paint))

    def _skirt(self, p3: np.ndarray, ppm: float, forward: np.ndarray) -> tuple[float, Callable[[], None]]:
        j, shape, mat = self._j, self.look.shape, self._mat
        lh, rh, lk, rk = (p3[j[n]] for n in ("l_hip", "r_hip", "l_knee", "r_knee"))
        top = 0.5 * (lh + rh)
        knees = 0.5 * (lk + rk)
        bottom = top + 0.85 * (knees - top)
        spine2 = _unit(bottom[:2] - top[:2], np.array([0.0, 1.0]))
        perp = np.array([-spine2[1], spine2[0]])
        lat = _unit(lh - rh, np.array([1.0, 0.0, 0.0]))
        lat = _unit(lat - forward * np.dot(lat, forward), lat)
        a_h = 0.5 * float(np.linalg.norm(lh - rh)) + shape.hip_pad
        a_k = max(0.5 * float(np.linalg.norm(lk - rk)) + shape.thigh[1] * 1.6, a_h * 1.25)
        stations = (
            (0.0, self._section(a_h * 1.02, lat, shape.hip_depth * 1.05, forward, perp)),
            (1.0, self._section(a_k, lat, shape.hip_depth * 1.5, forward, perp)),
        )
        paint_skirt = mat.bottom

        def paint(t: np.ndarray, u: np.ndarray, phi: np.ndarray, half: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
            # Pleats: a gentle light/dark modulation around the skirt.
            pleat = 1.0 + 0.07 * np.sin(phi * 9.0)
            return paint_skirt.base * pleat[..., None]

        return (0.5 * (top[2] + bottom[2]), lambda: self._ras.trunk(top, bottom, stations, (0.02, 0.0), ppm, paint))

    def _head(self, p3: np.ndarray, ppm: float, up_image: np.ndarray) -> list[tuple[float, Callable[[], None]]]:
        j, shape, mat, look = self._j, self.look.shape, self._mat, self.look
        centre, neck = p3[j["head"]], p3[j["neck"]]
        up = _unit(centre - neck, up_image)
        nose = p3[j["nose"]]
        face = nose - centre if np.isfinite(nose).all() else np.array([0.0, 0.0, -1.0])
        face = face - up * np.dot(face, up)
        face = _unit(face, _unit(np.array([0.0, 0.0, -1.0]) - up * -up[2], np.array([0.0, 0.0, -1.0])))
        side = np.cross(up, face)
        hr = shape.head_radius
        parts: list[tuple[float, Callable[[], None]]] = []
        if look.hair_style == "long":
            # Long hair: a tapering mass behind the head down to the shoulders.
            start = centre - face * hr * 0.35 + up * hr * 0.1
            end = neck - face * hr * 0.75 + up * hr * 0.2
            parts.append((0.5 * (start[2] + end[2]),
                          lambda: self._ras.capsule(start, end, hr * 1.02, hr * 0.85, ppm, ((1.0, mat.hair),))))
        eyes = [_unit(face * 0.86 + up * 0.16 + side * s, face).astype(np.float32) for s in (0.42, -0.42)]
        hair_style = look.hair_style
        skin, hair = mat.skin.base, mat.hair.base
        f32 = face.astype(np.float32)
        u32 = up.astype(np.float32)
        s32 = side.astype(np.float32)

        def paint(nx: np.ndarray, ny: np.ndarray, nz: np.ndarray) -> np.ndarray:
            df = nx * f32[0] + ny * f32[1] + nz * f32[2]
            du = nx * u32[0] + ny * u32[1] + nz * u32[2]
            # The hairline: how high up the head (du) hair starts, as a curve over front-back (df): at
            # the forehead, above the ears, down to the nape.
            if hair_style == "bald":
                is_hair = du > 0.75
            elif hair_style == "long":
                is_hair = du > -0.25 + 0.7 * df - 0.05 * df * df
            else:
                is_hair = du > 0.05 + 0.575 * df - 0.175 * df * df
            rgb = np.where(is_hair[..., None], hair, skin)
            for eye in eyes:
                rgb = np.where(((nx * eye[0] + ny * eye[1] + nz * eye[2]) > 0.988)[..., None], _EYE, rgb)
            # A mouth: a short horizontal line low on the front of the face.
            ds = nx * s32[0] + ny * s32[1] + nz * s32[2]
            in_mouth = (np.abs(du + 0.4) < 0.045) & (np.abs(ds) < 0.2) & (df > 0.7)
            return np.where(in_mouth[..., None], _MOUTH, rgb)

        if np.isfinite(nose).all():
            # The nose: a small skin capsule from inside the face out to the nose point.
            root = centre + face * hr * 0.6 - up * hr * 0.15
            parts.append((float(nose[2]), lambda: self._ras.capsule(root, nose, hr * 0.2, hr * 0.16, ppm,
                                                                     ((1.0, mat.skin),))))
        # Taller than wide, reaching further down (jaw) than up (the skull's centre is above the face's).
        chin, crown = centre - up * hr * 0.45, centre + up * hr * 0.2
        parts.append((float(centre[2]), lambda: self._ras.ellipsoid(chin, crown, hr, ppm, paint)))
        return parts



# ---------------------------------------------------------------------------------------------------
# Whole performances: a motion replayed on a character, framed by the framing rule, rendered.


def floor_line(camera_ty: float, scale: float, height: int, pitch_deg: float) -> float:
    """Image row where the backdrop's floor meets its wall.

    The cameras are weak-perspective, so the floor has no true horizon; the wall starts a fixed 0.1 of
    the canvas above the ground line, higher when the camera looks down (it sees more floor).
    """
    y = camera_ty - 0.1 * height - scale * 3.0 * math.sin(math.radians(pitch_deg))
    return float(np.clip(y, 0.2 * height, height - 1.0))


def _canvas_size(size: int | tuple[int, int]) -> tuple[int, int]:
    w, h = (size, size) if isinstance(size, (int, np.integer)) else size
    if int(w) < 16 or int(h) < 16:
        raise ValueError(f"canvas size must be at least 16 x 16 pixels, got {w} x {h}")
    return int(w), int(h)


def render_frames(xy: np.ndarray, depth: np.ndarray, px_per_m: float, look: Look, size: tuple[int, int],
                  joint_names: Sequence[str], floor_y: float) -> Iterator[np.ndarray]:
    """Render a sequence of projected poses, one frame at a time (memory stays bounded).

    Args:
        xy: [T, K, 2] pixel coordinates.
        depth: [T, K] metres, larger is farther.
        px_per_m: pixels per metre.
        look: appearance.
        size: (width, height).
        joint_names: the K joint names.
        floor_y: image row of the backdrop's floor line.

    Yields:
        [H, W, 3] uint8 RGB frames (each a new array).
    """
    w, h = size
    renderer = PerformerRenderer(look, make_background(w, h, look.backdrop, floor_y), joint_names)
    for t in range(xy.shape[0]):
        yield renderer.render(xy[t], depth[t], px_per_m, out=np.empty((h, w, 3), dtype=np.uint8))


def body25_track(xy: np.ndarray, joint_names: Sequence[str], fps: float, size: tuple[int, int]) -> PoseTrack:
    """A BODY_25 track of projected joints: joints with the same name copied, the others missing.

    Args:
        xy: [T, K, 2] pixel coordinates.
        joint_names: the K names (e.g. ``WORLD_JOINTS``).
        fps: frame rate.
        size: (width, height) of the canvas.
    """
    layout = BODY25
    joints = np.full((xy.shape[0], len(layout), 2), np.nan, dtype=np.float32)
    for k, name in enumerate(joint_names):
        if layout.has(name):
            joints[:, layout.index(name)] = xy[:, k]
    conf = np.where(np.isnan(joints[..., 0]), 0.0, 1.0).astype(np.float32)
    return PoseTrack(joints, conf, fps, size, layout.name)


def render_performance(
    motion: Motion3D,
    skeleton: Skeleton,
    look: Look,
    yaw: float,
    pitch: float = 0.0,
    size: int | tuple[int, int] = 256,
    start: int = 0,
    frames: int | None = None,
) -> tuple[Iterator[np.ndarray], PoseTrack, dict]:
    """Render ``motion`` performed by a character (``skeleton`` + ``look``) from a view.

    The fixed rule, so that rendering the reference character with the driver's motion and the
    reference's view is exactly the ground truth of a cloning run:

    1. the whole motion is replayed on ``skeleton`` (:func:`retarget.world.skeleton.retarget_3d`);
    2. frames ``start : start + frames`` are kept (the rendered clip);
    3. the view yaw is relative to the clip's average facing (:func:`retarget.world.camera.facing_angle`);
    4. framing (:func:`retarget.world.camera.frame_camera`): the ground under the clip's first root is at
       (W/2, 0.9 H) and the scale is 0.36 H pixels per metre.

    Args:
        motion: the motion (any character; it is retargeted).
        skeleton: bone lengths of the performer.
        look: appearance of the performer.
        yaw: view yaw in degrees (0 = front, +90 = the performer's left side).
        pitch: camera elevation in degrees (+ = from above).
        size: canvas side (square) or (width, height) in pixels.
        start: first frame of the clip.
        frames: number of frames (default: to the end).

    Returns:
        ``(frames, track, meta)``: an iterator of [H, W, 3] uint8 RGB frames, the BODY_25
        :class:`PoseTrack` of the exact projected joints, and a JSON-ready dict describing the render.
    """
    w, h = _canvas_size(size)
    total = motion.num_frames
    if not 0 <= start < total:
        raise ValueError(f"start frame {start} is outside the motion's {total} frames")
    stop = total if frames is None else start + int(frames)
    if frames is not None and (frames < 1 or stop > total):
        raise ValueError(f"frames {start}..{stop - 1} are outside the motion's {total} frames")
    positions = retarget_3d(motion, skeleton).positions[start:stop]  # [T, 18, 3] metres, Y up
    facing = facing_angle(positions)
    camera = frame_camera(yaw, pitch, (w, h))
    xy, depth = project(positions, camera, facing, origin=ground_origin(positions))  # [T, 18, 2], [T, 18]
    track = body25_track(xy, WORLD_JOINTS, motion.fps, (w, h))
    floor_y = floor_line(camera.ty, camera.scale, h, pitch)
    meta = {
        "motion": {"name": motion.name, "source": motion.source, "fps": motion.fps, "start": start,
                   "frames": int(stop - start), "total_frames": total},
        "character": {"skeleton": skeleton.name, "look": look.name, "height_m": skeleton.height,
                      "bone_lengths_m": skeleton.as_dict()},
        "camera": dataclasses.asdict(camera),
        "facing_deg": facing,
        "framing": {
            "rule": "retarget_3d on the whole motion, cut frames, yaw relative to the clip's mean facing, "
                    "ground under the clip's first root at (W/2, FRAME_GROUND*H), FRAME_SCALE*H px per metre",
            "FRAME_GROUND": FRAME_GROUND, "FRAME_SCALE": FRAME_SCALE,
        },
        "size": [w, h],
        "fps": motion.fps,
        "floor_y": floor_y,
        "look": look.to_dict(),
    }
    return render_frames(xy, depth, camera.scale, look, (w, h), WORLD_JOINTS, floor_y), track, meta


def save_performance(
    out: str | os.PathLike,
    motion: Motion3D,
    skeleton: Skeleton,
    look: Look,
    yaw: float,
    pitch: float = 0.0,
    size: int | tuple[int, int] = 256,
    start: int = 0,
    frames: int | None = None,
    overwrite: bool = False,
    extra_meta: Mapping[str, Mapping] | None = None,
    on_frame: Callable[[int], None] | None = None,
) -> Path:
    """Render a performance (see :func:`render_performance`) into a folder, atomically.

    Writes ``out/frames/frame_000000.png ...`` (RGB PNG), ``out/poses/`` (OpenPose BODY_25 JSON, one
    file per frame, of the projected joints; joints the world does not define and joints outside the
    canvas are written as missing, as a detector could not see them), ``out/poses.npz`` (the same track
    with every projected joint, also outside the canvas) and ``out/meta.json`` (the ``meta`` of
    :func:`render_performance`, updated with ``extra_meta`` section by section).

    Args:
        out: output folder; must not exist unless ``overwrite``.
        motion, skeleton, look, yaw, pitch, size, start, frames: as for :func:`render_performance`.
        overwrite: replace an existing ``out`` (only once the new one is complete).
        extra_meta: more entries for ``meta.json``; a dict value is merged into the section of that name.
        on_frame: called with the frame index after each frame is written (progress display).

    Returns:
        ``out``.
    """
    out = Path(out)
    check_new_output(out, overwrite)
    frame_iter, track, meta = render_performance(motion, skeleton, look, yaw, pitch, size, start, frames)
    for key, value in (extra_meta or {}).items():
        if isinstance(value, Mapping) and isinstance(meta.get(key), dict):
            meta[key].update(value)
        else:
            meta[key] = value
    w, h = track.image_size
    inside = (track.joints[..., 0] >= 0) & (track.joints[..., 1] >= 0)
    inside &= (track.joints[..., 0] <= w - 1) & (track.joints[..., 1] <= h - 1)
    seen = track.replace(confidence=np.where(inside, track.confidence, 0.0))
    with atomic_dir(out, overwrite=overwrite) as tmp:
        (tmp / "frames").mkdir()
        for t, frame in enumerate(frame_iter):
            path = tmp / "frames" / f"frame_{t:06d}.png"
            if not cv2.imwrite(str(path), np.ascontiguousarray(frame[..., ::-1])):
                raise OSError(f"{path}: could not write the PNG")
            if on_frame is not None:
                on_frame(t)
        write_track(seen, tmp / "poses", fmt="openpose")
        write_track(track, tmp / "poses.npz")
        meta["files"] = {"frames": "frames/frame_%06d.png", "poses": "poses/ (OpenPose BODY_25, in-canvas joints)",
                         "poses_npz": "poses.npz (every projected joint)"}
        meta["joints_outside_canvas"] = int((~inside & ~track.missing).sum())
        (tmp / "meta.json").write_text(json.dumps(meta, indent=1) + "\n")
    logger.info("wrote %s (%d frames)", out, track.num_frames)
    return out
