"""The rasteriser: colour and depth buffers of one canvas and the shaded primitives drawn into them.

Each primitive is rasterised with numpy inside its bounding box only, on float32 buffers allocated once
per video, with an anti-aliased edge, a per-pixel depth test (a near limb hides a far one) and Lambert
shading from a pseudo-normal:

- :meth:`Rasterizer.capsule`: a tapered capsule; the normal at a pixel comes from its distance to the
  axis (a round cross-section);
- :meth:`Rasterizer.trunk`: an elliptic cylinder whose cross-section turns along its axis
  (:mod:`clone.synth.cylinder`);
- :meth:`Rasterizer.ellipsoid`: a short capsule coloured by its 3D surface normal (a head).

Coordinates: points are [3] metres in camera coordinates (x right, y down, z away, larger is farther);
``ppm`` converts metres across the image to pixels (a weak-perspective camera), pixel centres at integers.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from clone.synth.cylinder import elliptic_cylinder
from clone.synth.paint import CHECKS, Bands, banded

# Direction towards the light in camera coordinates (x right, y down, z away): above, left, in front.
_LIGHT = np.array([-0.38, -0.72, -0.58], dtype=np.float64)
_LIGHT /= np.linalg.norm(_LIGHT)
_AMBIENT = 0.42
_DIFFUSE = 0.62

TrunkPaint = Callable[[np.ndarray, np.ndarray, np.ndarray, tuple[np.ndarray, np.ndarray]], np.ndarray]
NormalPaint = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]


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

    def _offsets(self, box: tuple[int, int, int, int], origin: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Pixel offsets from ``origin`` (x, y) over ``box``: ([1, w], [h, 1]) float32."""
        y0, y1, x0, x1 = box
        return self._xs[:, x0:x1] - np.float32(origin[0]), self._ys[y0:y1] - np.float32(origin[1])

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
        px, py = self._offsets(box, a2)  # [1, w], [h, 1]
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
        if any(p.pattern == CHECKS for _, p in bands):
            if length2 > 1e-6:
                lateral = (oy * np.float32(dx) - ox * np.float32(dy)) * np.float32(1.0 / math.sqrt(length2))
            else:
                lateral = ox
            v = np.arcsin(np.clip(lateral * inv_r, -1.0, 1.0)) * (r * np.float32(1.0 / ppm))
        self._composite(box, cover, z, banded(bands, t, u, v), nx, ny, nz)

    def trunk(self, top: np.ndarray, bottom: np.ndarray, stations: Sequence[tuple[float, np.ndarray]],
              caps: tuple[float, float], ppm: float, paint: TrunkPaint) -> None:
        """An elliptic cylinder along ``top`` -> ``bottom`` whose cross-section changes along the axis.

        Each station ``(t, M)`` gives the cross-section at axis fraction ``t`` as a 2x2 matrix mapping the
        unit circle to (image-lateral, depth) metres: columns are the two half axes (see
        :mod:`clone.synth.cylinder`).

        Args:
            top, bottom: [3] axis ends in metres (camera coordinates).
            stations: (t, [2, 2] M) sorted by t, covering 0 and 1.
            caps: how far (metres) the body continues, rounded, beyond the top and the bottom.
            ppm: pixels per metre.
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
        ends = (a2 - d * caps[0] * ppm, b2 + d * caps[1] * ppm)
        box = self._window(np.minimum(*ends) - reach, np.maximum(*ends) + reach)
        if box is None:
            return
        px, py = self._offsets(box, a2)  # [1, w], [h, 1]
        t_raw = (px * np.float32(d[0]) + py * np.float32(d[1])) * np.float32(1.0 / length_px)  # [h, w]
        x = (px * np.float32(perp[0]) + py * np.float32(perp[1])) * np.float32(1.0 / ppm)  # lateral metres
        caps_t = (caps[0] * ppm / length_px, caps[1] * ppm / length_px)  # caps as axis fractions
        cyl = elliptic_cylinder(t_raw, x, ts, ms, caps_t, length_px, ppm)
        z = t_raw * np.float32(bottom[2] - top[2]) + np.float32(top[2]) + cyl.zoff
        nx = cyl.n_lat * np.float32(perp[0]) + cyl.bend * np.float32(d[0])
        ny = cyl.n_lat * np.float32(perp[1]) + cyl.bend * np.float32(d[1])
        u = t_raw * np.float32(np.linalg.norm(bottom - top))
        self._composite(box, cyl.cover, z, paint(t_raw, u, cyl.phi, cyl.half), nx, ny, cyl.n_dep)

    def ellipsoid(self, pa: np.ndarray, pb: np.ndarray, r_m: float, ppm: float, paint: NormalPaint) -> None:
        """A short capsule (a slightly tall head) whose colour depends on the 3D surface normal.

        Args:
            pa, pb: [3] axis ends in metres (camera coordinates).
            r_m: radius in metres.
            ppm: pixels per metre.
            paint: ``(nx, ny, nz) -> [h, w, 3]`` colours from the unit surface normal.
        """
        a2, b2 = pa[:2] * ppm, pb[:2] * ppm
        r = r_m * ppm
        box = self._window(np.minimum(a2, b2) - r, np.maximum(a2, b2) + r)
        if box is None:
            return
        px, py = self._offsets(box, a2)  # [1, w], [h, 1]
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
