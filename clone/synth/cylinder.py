"""Per-pixel geometry of an elliptic cylinder seen along the camera axis (the torso and the skirt).

Pure numpy functions over a pixel window, all float32 ``[h, w]`` arrays. A pixel is given by its axis
fraction ``t_raw`` (0 at the top, 1 at the bottom, beyond the ends over the rounded caps) and its lateral
offset ``x`` in metres from the axis. The cross-section at ``t`` is a 2x2 matrix ``M`` mapping the unit
circle to (image-lateral, depth) metres: its columns are the ellipse's two half axes, and ``M`` is
interpolated linearly between a few stations along the axis. For a lateral offset x the visible (nearest)
surface point, its normal and its angle on the ellipse follow in closed form.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

Section = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]  # (m00, m01, m10, m11), each [h, w]


class CylinderPixels(NamedTuple):
    """What :func:`elliptic_cylinder` finds at each pixel of a window (all [h, w] float32).

    Attributes:
        cover: anti-aliased coverage in [0, 1].
        zoff: depth of the visible surface relative to the axis, metres (negative = nearer).
        n_lat, n_dep, bend: unit surface normal in (image-lateral, depth, along the axis).
        phi: angle on the cross-section (pi/2 = the second half axis, the front).
        half: lengths of the two half axes, metres.
    """

    cover: np.ndarray
    zoff: np.ndarray
    n_lat: np.ndarray
    n_dep: np.ndarray
    bend: np.ndarray
    phi: np.ndarray
    half: tuple[np.ndarray, np.ndarray]


def sections_at(t: np.ndarray, ts: np.ndarray, ms: np.ndarray) -> Section:
    """Cross-section matrices at axis fractions ``t`` [h, w], interpolated from stations ``ts`` [S], ``ms`` [S, 2, 2]."""
    m00, m01, m10, m11 = (np.interp(t, ts, ms[:, r, c]).astype(np.float32)
                          for r, c in ((0, 0), (0, 1), (1, 0), (1, 1)))
    return m00, m01, m10, m11


def end_taper(t_raw: np.ndarray, cap0: float, cap1: float) -> np.ndarray:
    """[h, w] factor on the squared half width: 1 between the ends, falling to 0 at the end of each cap.

    Past the top the half width shrinks like a parabola (sloping shoulders), past the bottom like an
    ellipse. ``cap0``, ``cap1`` are the caps' lengths as axis fractions.
    """
    over = np.where(t_raw < 0, -t_raw / np.float32(max(cap0, 1e-6)), (t_raw - 1) / np.float32(max(cap1, 1e-6)))
    np.clip(over, 0.0, 1.0, out=over)
    return 1.0 - np.where(t_raw < 0, over, over * over)


def coverage(x: np.ndarray, t_raw: np.ndarray, sxx: np.ndarray, end: np.ndarray, caps: tuple[float, float],
             length_px: float, ppm: float) -> np.ndarray:
    """[h, w] anti-aliased coverage from the signed distance to the silhouette, sideways and past the caps.

    Args:
        x: [h, w] lateral offset in metres.
        t_raw: [h, w] axis fraction.
        sxx: [h, w] squared half width in metres².
        end: [h, w] :func:`end_taper`.
        caps: the caps' lengths as axis fractions (top, bottom).
        length_px: axis length in pixels.
        ppm: pixels per metre.
    """
    half_w = np.sqrt(sxx * end)
    cover = (half_w - np.abs(x)) * np.float32(ppm) + 0.5
    # Along the axis the body ends where the caps end (the lateral test alone leaves a 1 px line there).
    beyond = np.maximum(-t_raw - np.float32(caps[0]), t_raw - np.float32(1.0 + caps[1])) * np.float32(length_px)
    np.minimum(cover, 0.5 - beyond, out=cover)
    np.clip(cover, 0.0, 1.0, out=cover)
    return cover


def nearest_depth(x: np.ndarray, m: Section, sxx: np.ndarray, det: np.ndarray) -> np.ndarray:
    """[h, w] depth offset (metres, from the axis) of the visible surface point at lateral offset ``x``."""
    m00, m01, m10, m11 = m
    sxz = m00 * m10 + m01 * m11
    root = np.sqrt(np.maximum(sxx - x * x, 0.0))
    abs_det = np.maximum(np.abs(det), 1e-6)
    inv_sxx = 1.0 / np.maximum(sxx, 1e-8)
    return (sxz * x - abs_det * root) * inv_sxx


def surface_normal(x: np.ndarray, zoff: np.ndarray, m: Section, det: np.ndarray, end: np.ndarray,
                   t_raw: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Unit normal ``(n_lat, n_dep, bend)`` facing the camera and the angle ``phi`` on the ellipse, each [h, w].

    The angle comes from (cos, sin) = M^-1 (x, zoff), the normal from M^-T (cos, sin); past the ends the
    surface bends over the cap, like a dome.
    """
    m00, m01, m10, m11 = m
    inv_det = 1.0 / np.where(det >= 0, np.maximum(det, 1e-6), np.minimum(det, -1e-6))
    c = (m11 * x - m01 * zoff) * inv_det
    s = (m00 * zoff - m10 * x) * inv_det
    n_lat = (m11 * c - m10 * s) * inv_det
    n_dep = (m00 * s - m01 * c) * inv_det
    bend = np.sqrt(np.maximum(1.0 - end, 0.0)) * np.sign(t_raw - 0.5)
    norm = 1.0 / np.maximum(np.sqrt(n_lat * n_lat + n_dep * n_dep + bend * bend), 1e-6)
    flip = np.where(n_dep > 0, -norm, norm)  # the visible side faces the camera
    n_lat *= flip
    n_dep *= flip
    bend *= np.abs(flip)
    return n_lat, n_dep, bend, np.arctan2(s, c)


def elliptic_cylinder(t_raw: np.ndarray, x: np.ndarray, ts: np.ndarray, ms: np.ndarray,
                      caps: tuple[float, float], length_px: float, ppm: float) -> CylinderPixels:
    """Coverage, visible depth, normal and texture angle of an elliptic cylinder over a pixel window.

    Args:
        t_raw: [h, w] axis fraction of each pixel (0 top, 1 bottom, outside [0, 1] over the caps).
        x: [h, w] lateral offset of each pixel from the axis, metres.
        ts: [S] station axis fractions, sorted, covering 0 and 1.
        ms: [S, 2, 2] cross-section matrices at the stations.
        caps: how far the body continues past the top and the bottom, as axis fractions.
        length_px: axis length in pixels.
        ppm: pixels per metre.
    """
    m = sections_at(np.clip(t_raw, 0.0, 1.0), ts, ms)
    m00, m01, m10, m11 = m
    sxx = m00 * m00 + m01 * m01  # squared half width
    det = m00 * m11 - m01 * m10
    end = end_taper(t_raw, *caps)
    cover = coverage(x, t_raw, sxx, end, caps, length_px, ppm)
    zoff = nearest_depth(x, m, sxx, det)
    n_lat, n_dep, bend, phi = surface_normal(x, zoff, m, det, end, t_raw)
    half = (np.sqrt(m00 * m00 + m10 * m10), np.sqrt(m01 * m01 + m11 * m11))
    return CylinderPixels(cover, zoff, n_lat, n_dep, bend, phi, half)
