"""Rotation matrices from axis angles in degrees: one axis, or several composed in a given order.

Both BVH channels and Acclaim ASF/AMC angles are degrees about the coordinate axes; the two formats
differ in how they compose them: BVH in channel order about moving axes (``euler_matrices``), Acclaim
about fixed axes, first letter first (``acclaim_rotation``).
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType

import numpy as np

from pose_io.errors import InputError

# Axis letter -> column of a 3-vector.
AXES: Mapping[str, int] = MappingProxyType({"X": 0, "Y": 1, "Z": 2})


def axis_rotations(axis: int, degrees: np.ndarray) -> np.ndarray:
    """Rotation matrices about one coordinate axis.

    Args:
        axis: 0, 1 or 2 for X, Y, Z.
        degrees: [...] angles in degrees (right-handed, counter-clockwise looking down the axis).

    Returns:
        [..., 3, 3] float64 rotation matrices.
    """
    rad = np.deg2rad(np.asarray(degrees, dtype=np.float64))
    c, s = np.cos(rad), np.sin(rad)
    out = np.zeros(rad.shape + (3, 3))
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    out[..., axis, axis] = 1.0
    out[..., i, i] = c
    out[..., j, j] = c
    out[..., i, j] = -s
    out[..., j, i] = s
    return out


def euler_matrices(angles: np.ndarray, order: str) -> np.ndarray:
    """Compose axis rotations in ``order``: ``order="ZXY"`` gives ``Rz(a0) @ Rx(a1) @ Ry(a2)``.

    Args:
        angles: [..., len(order)] degrees, one column per letter of ``order``.
        order: axis letters, e.g. ``"ZXY"``.

    Returns:
        [..., 3, 3] float64.
    """
    angles = np.asarray(angles, dtype=np.float64)
    out = np.broadcast_to(np.eye(3), angles.shape[:-1] + (3, 3)).copy()
    for k, letter in enumerate(order.upper()):
        out = out @ axis_rotations(AXES[letter], angles[..., k])
    return out


def acclaim_rotation(xyz_degrees: np.ndarray, order: str) -> np.ndarray:
    """Acclaim rotation: about the axes in ``order``, each in the fixed frame, the first letter first.

    ``order="XYZ"`` gives ``Rz @ Ry @ Rx``.

    Args:
        xyz_degrees: [..., 3] angles about x, y, z (always in that column order).
        order: a permutation of ``"XYZ"``.

    Returns:
        [..., 3, 3] float64.

    Raises:
        InputError: ``order`` is not a permutation of XYZ (an ASF's ``axis`` or ``:root`` line).
    """
    order = order.upper()
    if sorted(order) != ["X", "Y", "Z"]:
        raise InputError(f"ASF rotation order must be a permutation of XYZ, got {order!r}")
    cols = [AXES[c] for c in reversed(order)]
    return euler_matrices(np.asarray(xyz_degrees)[..., cols], order[::-1])


__all__ = ["AXES", "acclaim_rotation", "axis_rotations", "euler_matrices"]
