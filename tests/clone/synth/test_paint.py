"""Paints and per-body-part materials."""

from __future__ import annotations

import dataclasses

import numpy as np

from clone.synth import Paint, get_look
from clone.synth.paint import CHECKS, STRIPES, Materials, banded, rgb

RED, WHITE = rgb((255, 0, 0)), rgb((255, 255, 255))


def test_a_solid_paint_is_one_broadcastable_colour() -> None:
    colours = Paint.solid((10, 20, 30)).colours(np.zeros((4, 5), np.float32), None)
    assert colours.shape == (1, 1, 3) and colours.dtype == np.float32
    assert colours.tolist() == [[[10.0, 20.0, 30.0]]]


def test_stripes_run_along_the_body_with_their_period() -> None:
    paint = Paint(RED, WHITE, STRIPES, period=0.25)
    u = (np.arange(2560, dtype=np.float32) / 1024)[None, :]  # ten periods, 256 exact samples each
    colours = paint.colours(u, None)
    accent = (colours == WHITE).all(-1)
    assert colours.shape == (1, 2560, 3)
    assert abs(accent.mean() - 0.4) < 0.01  # the accent is 0.4 of each period
    # Shifting by one period gives the same colours.
    np.testing.assert_array_equal(accent[0, :-256], accent[0, 256:])


def test_checks_alternate_along_and_around() -> None:
    paint = Paint(RED, WHITE, CHECKS, period=0.2)  # squares of 0.1 m
    u = np.array([[0.05, 0.15], [0.05, 0.15]], dtype=np.float32)
    v = np.array([[0.05, 0.05], [0.15, 0.15]], dtype=np.float32)
    accent = (paint.colours(u, v) == WHITE).all(-1)
    assert accent.tolist() == [[False, True], [True, False]]
    # Without an "around" coordinate checks fall back to stripes.
    assert (paint.colours(u, None) == paint.colours(u, v)).all(-1).any()


def test_bands_switch_paint_along_the_axis() -> None:
    bands = ((0.55, Paint.solid((1, 1, 1))), (1.0, Paint.solid((2, 2, 2))))
    t = np.array([[0.0, 0.5, 0.6, 1.0]], dtype=np.float32)
    colours = banded(bands, t, t, None)
    assert colours[0, :, 0].tolist() == [1.0, 1.0, 2.0, 2.0]


def test_materials_follow_the_clothes() -> None:
    look = dataclasses.replace(get_look("average"), sleeves="short", bottom_style="shorts", pattern="checks")
    mat = Materials.of(look)
    assert [t for t, _ in mat.upper_arm] == [0.55, 1.0]
    assert mat.upper_arm[0][1] is mat.shirt and mat.upper_arm[1][1] is mat.skin
    assert mat.forearm == ((1.0, mat.skin),) and mat.shin == ((1.0, mat.skin),)
    assert mat.thigh == ((0.6, mat.bottom), (1.0, mat.skin))
    assert mat.shirt.pattern == CHECKS and mat.shirt.period == look.pattern_period
    long = Materials.of(dataclasses.replace(look, sleeves="long", bottom_style="trousers"))
    assert long.upper_arm == ((1.0, long.shirt),) and long.forearm[0] == (0.96, long.shirt)
    assert long.thigh == ((1.0, long.bottom),) and long.shin == ((1.0, long.bottom),)
    skirt = Materials.of(dataclasses.replace(look, bottom_style="skirt"))
    assert skirt.thigh == ((1.0, skirt.skin),)
