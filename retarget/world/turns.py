"""Whole-body turns added to captured motion in 3D, before projection, and how far a window turns.

Most capture clips face one way: in the world built from the shipped collection the median window turns by
12° and one training window in eleven by more than 90°, one validation window in 37. Real dancers and fashion
models turn. A :class:`Turn` rotates a window's body about the vertical axis through its root by an angle that
grows from 0 to ``angle_deg`` between two frames (smoothstep: slow, fast, slow), and turns the root's path with
it (each frame's step is rotated by the angle reached then), as a person turning while walking walks on in the
new direction. Bone lengths, heights and the contact of a standing foot with the ground are unchanged.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from retarget.world.camera import facing_vectors
from retarget.world.skeleton import joint_index

_ROOT = joint_index("mid_hip")


@dataclass(frozen=True)
class Turn:
    """A turn about the vertical axis.

    Attributes:
        angle_deg: total angle, degrees (+ = the facing angle of ``camera.facing_angle`` grows, from +Z
            towards +X).
        start: frame where the turn begins.
        duration: frames it lasts (at least 1).
    """

    angle_deg: float
    start: float
    duration: float


def draw_turn(rng: np.random.Generator, length: int, angle_range: tuple[float, float] = (90.0, 360.0),
              shortest: float = 0.3) -> Turn:  # fmt: skip
    """A random turn within a ``length``-frame window: angle uniform in ``angle_range`` either way, lasting a
    share in [``shortest``, 1] of the window (so speeds vary about fivefold), starting anywhere it fits."""
    lo, hi = angle_range
    angle = rng.uniform(lo, hi) * (1.0 if rng.random() < 0.5 else -1.0)
    duration = rng.uniform(shortest, 1.0) * max(length - 1, 1)
    start = rng.uniform(0.0, max(length - 1 - duration, 0.0))
    return Turn(float(angle), float(start), float(max(duration, 1.0)))


def turn_angles(turn: Turn, length: int) -> np.ndarray:
    """[length] radians the body has turned by at each frame."""
    u = np.clip((np.arange(length) - turn.start) / turn.duration, 0.0, 1.0)
    return np.radians(turn.angle_deg) * u * u * (3.0 - 2.0 * u)


def _rotate_y(xz: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """Rotate [T, ..., 2] (x, z) points about +Y by [T] radians (+Z towards +X for positive angles)."""
    shape = (len(angles),) + (1,) * (xz.ndim - 2)
    cos, sin = np.cos(angles).reshape(shape), np.sin(angles).reshape(shape)
    x, z = xz[..., 0], xz[..., 1]
    return np.stack([cos * x + sin * z, -sin * x + cos * z], axis=-1)


def apply_turn(positions: np.ndarray, turn: Turn) -> np.ndarray:
    """The window turning as ``turn`` says: [T, 18, 3] metres (Y up) -> [T, 18, 3] float32.

    Every frame's joints are rotated about the vertical through that frame's root by the angle reached, and
    the root's horizontal steps by the same angle, so the path bends with the body; frame 0's root stays.
    """
    pos = np.asarray(positions, dtype=np.float64)
    angles = turn_angles(turn, len(pos))  # [T]
    root = pos[:, _ROOT]  # [T, 3]
    local = pos - root[:, None]  # [T, 18, 3]
    out = local.copy()
    out[..., [0, 2]] = _rotate_y(local[..., [0, 2]], angles)
    steps = np.diff(root[:, [0, 2]], axis=0)  # [T - 1, 2]
    path = np.concatenate([root[:1, [0, 2]], root[0, [0, 2]] + np.cumsum(_rotate_y(steps, angles[1:]), axis=0)])
    out[..., 0] += path[:, None, 0]
    out[..., 2] += path[:, None, 1]
    out[..., 1] += root[:, None, 1]
    return out.astype(np.float32)


def facing_change(positions: np.ndarray) -> np.ndarray:
    """[...] degrees between the most different facings within each window of [..., T, 18, 3] (unwrapped, so a
    full spin reads 360)."""
    fwd = facing_vectors(positions)  # [..., T, 2]
    angles = np.unwrap(np.arctan2(fwd[..., 0], fwd[..., 1]), axis=-1)
    return np.degrees(angles.max(axis=-1) - angles.min(axis=-1))


__all__ = ["Turn", "apply_turn", "draw_turn", "facing_change", "turn_angles"]
