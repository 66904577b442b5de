"""The rasteriser: depth-tested, anti-aliased, shaded primitives."""

from __future__ import annotations

import numpy as np
import pytest

from clone.synth import Paint, Rasterizer


@pytest.mark.parametrize("blue_first", [False, True])
@pytest.mark.parametrize("blue_depth", [4.0, 6.0])
def test_nearer_capsule_hides_the_one_behind(blue_first: bool, blue_depth: float) -> None:
    grey = np.full((64, 64, 3), 128, dtype=np.uint8)
    ras = Rasterizer(grey)
    # End points in metres at 100 px/m: a horizontal red and a vertical blue capsule crossing at (32, 32).
    red = ([0.10, 0.32, 5.0], [0.54, 0.32, 5.0], ((1.0, Paint.solid((255, 0, 0))),))
    blue = ([0.32, 0.10, blue_depth], [0.32, 0.54, blue_depth], ((1.0, Paint.solid((0, 0, 255))),))
    for pa, pb, bands in (blue, red) if blue_first else (red, blue):
        ras.capsule(np.array(pa), np.array(pb), 0.06, 0.06, 100.0, bands)  # 6 px radius
    image = ras.image()
    centre = image[32, 32].astype(int)
    if blue_depth < 5.0:
        assert centre[2] > 60 and centre[0] == 0
    else:
        assert centre[0] > 60 and centre[2] == 0
    # Away from the crossing each capsule shows its own colour, shaded but not mixed.
    assert image[32, 14, 0] > 60 and image[32, 14, 2] == 0
    assert image[14, 32, 2] > 60 and image[14, 32, 0] == 0
    assert (image[2, 2] == 128).all()


def test_rasterizer_rejects_a_bad_background() -> None:
    with pytest.raises(ValueError, match="uint8"):
        Rasterizer(np.zeros((8, 8, 3), dtype=np.float32))


def test_ellipsoid_is_coloured_by_its_surface_normal() -> None:
    ras = Rasterizer(np.zeros((64, 64, 3), dtype=np.uint8))

    def paint(nx: np.ndarray, ny: np.ndarray, nz: np.ndarray) -> np.ndarray:
        # Green where the surface faces the camera (nz < 0 is towards it), red on the rim.
        return np.where((nz < -0.9)[..., None], np.float32([0, 255, 0]), np.float32([255, 0, 0]))

    # A ball of radius 0.1 m at 100 px/m (10 px) centred at pixel (32, 32), 5 m away.
    centre = np.array([0.32, 0.32, 5.0])
    ras.ellipsoid(centre, centre, 0.1, 100.0, paint)
    image = ras.image().astype(int)
    assert image[32, 32, 1] > 0 and image[32, 32, 0] == 0
    assert image[32, 32 + 9, 0] > 0 and image[32, 32 + 9, 1] == 0
    # The depth buffer holds the near surface: 5 m minus the radius at the centre.
    assert ras.depth[32, 32] == pytest.approx(4.9, abs=1e-3)
    covered = np.isfinite(ras.depth).sum()
    assert abs(covered - np.pi * 10**2) < 0.1 * np.pi * 10**2
    ras.clear()
    assert not np.isfinite(ras.depth).any() and (ras.image() == 0).all()


def test_trunk_is_as_wide_as_its_cross_section() -> None:
    ras = Rasterizer(np.zeros((80, 80, 3), dtype=np.uint8))
    # A vertical cylinder facing the camera: half width 0.15 m sideways, 0.1 m deep; 100 px/m.
    section = np.array([[0.15, 0.0], [0.0, -0.1]])
    top, bottom = np.array([0.4, 0.1, 5.0]), np.array([0.4, 0.7, 5.0])
    fronts = []

    def paint(t: np.ndarray, u: np.ndarray, phi: np.ndarray, half: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
        fronts.append(phi)
        return np.full(t.shape + (3,), 200, dtype=np.float32)

    ras.trunk(top, bottom, ((0.0, section), (1.0, section)), (0.0, 0.0), 100.0, paint)
    row = np.isfinite(ras.depth[40])
    assert abs(int(row.sum()) - 30) <= 1  # 2 x 0.15 m at 100 px/m
    assert ras.depth[40, 40] == pytest.approx(4.9, abs=1e-3)  # the front of the cylinder
    assert np.isfinite(ras.depth[12:68, 40]).all() and not np.isfinite(ras.depth[:8, 40]).any()
    # One paint call over the whole window, whose centre line is the front (phi = pi/2).
    assert len(fronts) == 1 and fronts[0].ndim == 2
    assert np.abs(fronts[0] - np.pi / 2).min() < 0.05
