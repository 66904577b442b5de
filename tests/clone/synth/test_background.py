"""The fixed background: wall, floor and the floor line."""

from __future__ import annotations

import numpy as np
import pytest

from clone.synth import get_look, make_background
from clone.synth.background import floor_line


def test_background_depends_on_the_seed_only() -> None:
    look_a, look_b = get_look("average"), get_look("child")
    a = make_background(64, 48, look_a.backdrop, 36.0)
    assert a.shape == (48, 64, 3) and a.dtype == np.uint8
    assert a.tobytes() == make_background(64, 48, look_a.backdrop, 36.0).tobytes()
    assert a.tobytes() != make_background(64, 48, look_b.backdrop, 36.0).tobytes()


def test_floor_below_the_floor_line_wall_above() -> None:
    look = get_look("average")
    image = make_background(64, 64, look.backdrop, 32.0).astype(int)
    wall, floor = image[:30].reshape(-1, 3).mean(0), image[34:].reshape(-1, 3).mean(0)
    # The average look's wall is a light grey-blue, its floor a brown wood.
    assert wall[2] > wall[0] and floor[0] > floor[2] + 20
    # A floor line below the canvas leaves only wall.
    only_wall = make_background(64, 64, look.backdrop, 200.0).astype(int)
    assert only_wall[-1].mean(0)[2] > only_wall[-1].mean(0)[0]


def test_floor_line_sits_above_the_ground_and_rises_when_looking_down() -> None:
    level = floor_line(camera_ty=230.4, scale=92.16, height=256, pitch_deg=0.0)
    assert level == pytest.approx(230.4 - 25.6)
    assert floor_line(230.4, 92.16, 256, 10.0) < level
    # Clipped to the canvas: never above 0.2 H, never below the last row.
    assert floor_line(230.4, 92.16, 256, 80.0) == pytest.approx(0.2 * 256)
    assert floor_line(1000.0, 92.16, 256, 0.0) == 255.0
