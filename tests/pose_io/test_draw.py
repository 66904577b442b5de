"""pose_io.draw: one OpenPose-style pose per call, drawn in place; missing joints are left out."""

from __future__ import annotations

import numpy as np
import pytest

from pose_io import BODY15, JointLayout
from pose_io.draw import blank_canvas, draw_pose

STICK = JointLayout("stick", ("a", "b", "c"), (("a", "b"), ("b", "c")), ((255, 0, 0), (0, 255, 0), (0, 0, 255)))


def test_blank_canvas():
    canvas = blank_canvas(40, 30, (10, 20, 30))
    assert canvas.shape == (30, 40, 3) and canvas.dtype == np.uint8
    assert (canvas.reshape(-1, 3) == [10, 20, 30]).all()
    assert (blank_canvas(5, 4) == 0).all()


def test_draws_in_place_with_the_limb_colour_of_its_child_joint():
    canvas = blank_canvas(64, 64)
    joints = np.array([[10.0, 10.0], [10.0, 50.0], [50.0, 50.0]])
    out = draw_pose(canvas, joints, STICK, thickness=3, antialias=False)
    assert out is canvas
    assert tuple(canvas[30, 10]) == (0, 255, 0)  # middle of a -> b: b's colour
    assert tuple(canvas[50, 30]) == (0, 0, 255)  # middle of b -> c: c's colour
    assert tuple(canvas[10, 10]) == (255, 0, 0)  # joint a
    assert tuple(canvas[30, 40]) == (0, 0, 0)  # away from the figure


def test_without_antialiasing_only_layout_colours_appear():
    canvas = blank_canvas(64, 64)
    joints = np.array([[10.3, 12.7], [20.5, 49.1], [51.2, 40.6]])
    draw_pose(canvas, joints, STICK, antialias=False)
    colours = {tuple(c) for c in canvas.reshape(-1, 3)}
    assert colours <= {(0, 0, 0), *STICK.colors}
    smooth = draw_pose(blank_canvas(64, 64), joints, STICK)
    assert len({tuple(c) for c in smooth.reshape(-1, 3)}) > len(colours)  # anti-aliased edges blend


def test_a_missing_joint_drops_its_limbs_and_itself():
    joints = np.array([[10.0, 10.0], [np.nan, np.nan], [50.0, 50.0]])
    canvas = draw_pose(blank_canvas(64, 64), joints, STICK, antialias=False)
    assert tuple(canvas[10, 10]) == (255, 0, 0) and tuple(canvas[50, 50]) == (0, 0, 255)
    assert not (canvas == (0, 255, 0)).all(axis=-1).any()  # nothing of b or its limb
    assert tuple(canvas[30, 30]) == (0, 0, 0)
    empty = draw_pose(blank_canvas(16, 16), np.full((3, 2), np.nan), STICK)
    assert not empty.any()


def test_far_away_points_are_clipped_not_overflowing():
    joints = np.array([[32.0, 32.0], [1e9, -1e9], [-1e12, 5.0]])
    canvas = draw_pose(blank_canvas(64, 64), joints, STICK)
    assert canvas[32, 32].any()


def test_default_thickness_scales_with_the_canvas():
    joints = np.array([[0.25, 0.2], [0.25, 0.8], [0.75, 0.8]])

    def width(size: int) -> int:
        canvas = draw_pose(blank_canvas(size, size), joints * size, STICK, antialias=False)
        return int((canvas[size // 2, :, 1] == 255).sum())  # the a -> b limb across the middle row

    assert width(512) == pytest.approx(4 * width(128), abs=2)


def test_a_body15_pose_is_deterministic(walking_track):
    pose = walking_track.to_layout("body15").joints[0]
    a = draw_pose(blank_canvas(640, 480), pose, BODY15)
    b = draw_pose(blank_canvas(640, 480), pose, BODY15)
    np.testing.assert_array_equal(a, b)
    assert a.any(axis=-1).sum() > 1000
