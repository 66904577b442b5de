"""The elliptic cylinder's per-pixel geometry: known values on a cylinder facing the camera."""

from __future__ import annotations

import numpy as np
import pytest

from clone.synth.cylinder import coverage, elliptic_cylinder, end_taper, sections_at

A, B = 0.2, 0.1  # half width sideways and half depth, metres
PPM = 100.0
# Columns: the lateral half axis, and the forward half axis pointing at the camera (negative depth).
FACING = np.array([[A, 0.0], [0.0, -B]], dtype=np.float32)


def pixels(x: list[float], t: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """([1, n] axis fractions, [1, n] lateral offsets) of a row of pixels."""
    xs = np.array([x], dtype=np.float32)
    return np.full_like(xs, t), xs


def facing_cylinder(x: list[float], t: float = 0.5, caps: tuple[float, float] = (0.1, 0.1)):
    t_raw, xs = pixels(x, t)
    ts = np.array([0.0, 1.0], dtype=np.float32)
    return elliptic_cylinder(t_raw, xs, ts, np.stack([FACING, FACING]), caps, 50.0, PPM)


def test_the_visible_surface_is_the_near_half_of_the_ellipse() -> None:
    xs = [0.0, 0.5 * A, -0.5 * A]
    cyl = facing_cylinder(xs)
    expected = -B * np.sqrt(1.0 - (np.array(xs) / A) ** 2)
    np.testing.assert_allclose(cyl.zoff[0], expected, atol=1e-6)
    # The front (phi = pi/2) faces the camera; the texture angle runs symmetrically to either side.
    assert cyl.phi[0, 0] == pytest.approx(np.pi / 2, abs=1e-6)
    assert cyl.phi[0, 1] + cyl.phi[0, 2] == pytest.approx(np.pi, abs=1e-5)
    np.testing.assert_allclose([h[0, 0] for h in cyl.half], [A, B], atol=1e-7)


def test_normals_are_unit_face_the_camera_and_follow_the_ellipse() -> None:
    xs = [0.0, 0.5 * A, 0.9 * A, -0.7 * A]
    cyl = facing_cylinder(xs)
    norm = np.sqrt(cyl.n_lat**2 + cyl.n_dep**2 + cyl.bend**2)
    np.testing.assert_allclose(norm, 1.0, atol=1e-5)
    assert (cyl.n_dep < 0).all() and (cyl.bend == 0).all()
    # The gradient of (x/a)² + (z/b)² is parallel to (x/a², z/b²).
    x, z = np.array(xs), cyl.zoff[0]
    grad = np.stack([x / A**2, z / B**2])
    grad /= np.linalg.norm(grad, axis=0)
    np.testing.assert_allclose(np.stack([cyl.n_lat[0], cyl.n_dep[0]]), grad, atol=1e-5)


def test_coverage_is_full_inside_half_at_the_edge_and_zero_outside() -> None:
    cyl = facing_cylinder([0.0, A - 0.02, A, A + 0.02])
    np.testing.assert_allclose(cyl.cover[0], [1.0, 1.0, 0.5, 0.0], atol=1e-5)
    # Past the end of a cap nothing is covered, however close to the axis.
    assert facing_cylinder([0.0], t=1.2).cover[0, 0] == 0.0


def test_ends_round_off_over_the_caps() -> None:
    t_raw = np.array([[-0.05, 0.0, 0.5, 1.0, 1.05, 1.1]], dtype=np.float32)
    end = end_taper(t_raw, 0.1, 0.1)
    # A parabola past the top (sloping shoulders), an ellipse past the bottom, 1 in between.
    np.testing.assert_allclose(end[0], [0.5, 1.0, 1.0, 1.0, 0.75, 0.0], atol=1e-6)
    cover = coverage(np.zeros_like(t_raw), t_raw, np.full_like(t_raw, A * A), end, (0.1, 0.1), 50.0, PPM)
    assert (cover[0, :5] == 1.0).all() and cover[0, 5] == pytest.approx(0.5, abs=1e-4)


def test_sections_are_interpolated_between_stations() -> None:
    ts = np.array([0.0, 1.0], dtype=np.float32)
    ms = np.stack([FACING, 3.0 * FACING])
    m00, m01, m10, m11 = sections_at(np.array([[0.0, 0.5, 1.0]], dtype=np.float32), ts, ms)
    np.testing.assert_allclose(m00[0], [A, 2 * A, 3 * A], rtol=1e-6)
    np.testing.assert_allclose(m11[0], [-B, -2 * B, -3 * B], rtol=1e-6)
    assert not m01.any() and not m10.any() and m00.dtype == np.float32
