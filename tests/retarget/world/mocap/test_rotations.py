"""Axis, Euler (BVH) and fixed-axis (Acclaim) rotation matrices."""

from __future__ import annotations

import numpy as np
import pytest

from pose_io.errors import InputError
from retarget.world.mocap.rotations import acclaim_rotation, axis_rotations, euler_matrices


@pytest.mark.parametrize(
    ("axis", "vector", "turned"),
    [(0, [0, 1, 0], [0, 0, 1]), (1, [0, 0, 1], [1, 0, 0]), (2, [1, 0, 0], [0, 1, 0])],
)
def test_quarter_turns_are_counter_clockwise(axis: int, vector: list[int], turned: list[int]) -> None:
    np.testing.assert_allclose(axis_rotations(axis, 90.0) @ np.array(vector, dtype=float), turned, atol=1e-12)


def test_euler_matrices_are_rotations_and_broadcast() -> None:
    angles = np.random.default_rng(0).uniform(-180, 180, size=(4, 5, 3))
    rot = euler_matrices(angles, "zxy")
    assert rot.shape == (4, 5, 3, 3) and rot.dtype == np.float64
    eye = np.broadcast_to(np.eye(3), rot.shape)
    np.testing.assert_allclose(rot @ np.swapaxes(rot, -1, -2), eye, atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(rot), 1.0, atol=1e-12)
    # Two channels only (a joint with Xrotation Yrotation): still [..., 3, 3].
    assert euler_matrices(angles[..., :2], "XY").shape == (4, 5, 3, 3)


def test_acclaim_order_is_fixed_axes_first_letter_first() -> None:
    xyz = np.array([10.0, -35.0, 60.0])
    rx, ry, rz = (axis_rotations(a, xyz[a]) for a in range(3))
    np.testing.assert_allclose(acclaim_rotation(xyz, "XYZ"), rz @ ry @ rx, atol=1e-12)
    np.testing.assert_allclose(acclaim_rotation(xyz, "zyx"), rx @ ry @ rz, atol=1e-12)
    with pytest.raises(InputError, match="permutation of XYZ"):
        acclaim_rotation(xyz, "XYY")
