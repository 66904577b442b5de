"""New motions made from captured ones in 3D, before projection: upper/lower-body splicing and joint-angle noise.

The capture collection holds a few hundred clips; every window's arms move with its own legs. Two variations
make motions it does not hold while keeping what a body can do:

- :func:`splice`: the legs and root path of one window with the torso, arms and head of another, on the same
  character. The upper body's bones are turned about the vertical, frame by frame, by the angle between the two
  windows' hip lines, so the chest faces where the pelvis does; the feet, and so their contact with the ground,
  are those of the lower window.
- :func:`bend`: a small, slowly varying rotation of every upper-body bone about its parent joint, passed down
  the chain (a shoulder's rotation carries the elbow and wrist), as a change of joint angles would. The legs keep
  theirs, so standing feet do not slide. Bone lengths are unchanged by both.
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.spatial.transform import Rotation

from retarget.world.skeleton import BONE_NAMES, BONES, ROOT, WORLD_JOINTS, assemble, bone_vectors, joint_index

_ROOT = joint_index(ROOT)
_L_HIP, _R_HIP = joint_index("l_hip"), joint_index("r_hip")
# Bones of the legs (from the root to the toes): they come from the lower window and are never bent.
_LEG_BONES = tuple(i for i, name in enumerate(BONE_NAMES) if name.endswith(("hip", "knee", "ankle", "toe")))
UPPER_BONES: tuple[int, ...] = tuple(i for i in range(len(BONES)) if i not in _LEG_BONES)
# The bone whose child joint is each bone's parent joint (-1: the bone starts at the root).
_PARENT_BONE = np.array([BONE_NAMES.index(p) if p in BONE_NAMES else -1 for p, _ in BONES], dtype=np.int64)
# Knots per window of the noise's smooth path (about one every 20 frames of a 64-frame window).
_KNOTS_PER_FRAME = 1 / 20


def _hip_heading(positions: np.ndarray) -> np.ndarray:
    """[T] complex unit numbers: the direction of each frame's hip line (right hip -> left hip) in the x-z
    plane."""
    hips = positions[:, _L_HIP, [0, 2]] - positions[:, _R_HIP, [0, 2]]  # [T, 2]
    heading = hips[:, 0] + 1j * hips[:, 1]
    size = np.abs(heading)
    return np.where(size > 1e-9, heading / np.maximum(size, 1e-9), 1.0 + 0j)


def splice(lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """The legs and root path of ``lower`` with the torso, arms and head of ``upper``.

    Args:
        lower: [T, 18, 3] metres (Y up) of one character.
        upper: [T, 18, 3] another window of the same character (same bone lengths).

    Returns:
        [T, 18, 3] float32. The upper body's bone vectors are turned about +Y, per frame, by the angle between
        the hip lines of ``upper`` and ``lower``; every leg joint and the root are ``lower``'s.
    """
    lower = np.asarray(lower, dtype=np.float64)
    upper = np.asarray(upper, dtype=np.float64)
    if lower.shape != upper.shape or lower.shape[1:] != (len(WORLD_JOINTS), 3):
        raise ValueError(f"splice needs two [T, {len(WORLD_JOINTS)}, 3] windows of one length, got "
                         f"{lower.shape} and {upper.shape}")
    vectors = bone_vectors(lower)  # [T, 17, 3]
    turn = _hip_heading(lower) / _hip_heading(upper)  # [T] rotation taking upper's hip line onto lower's
    up = bone_vectors(upper)[:, UPPER_BONES]  # [T, U, 3]
    xz = (up[..., 0] + 1j * up[..., 2]) * turn[:, None]
    vectors[:, UPPER_BONES, 0] = xz.real
    vectors[:, UPPER_BONES, 1] = up[..., 1]
    vectors[:, UPPER_BONES, 2] = xz.imag
    return assemble(lower[:, _ROOT], vectors).astype(np.float32)


def draw_bend(rng: np.random.Generator, length: int, sigma_deg: float) -> np.ndarray:
    """[length, U, 3] rotation vectors (radians) for :func:`bend`: per upper-body bone, a smooth path through
    knots about 20 frames apart whose rotation angle has an rms of ``sigma_deg`` (each axis drawn from
    N(0, ``sigma_deg`` / sqrt 3), clipped at 2.5 of that)."""
    if sigma_deg < 0:
        raise ValueError("sigma_deg must be >= 0")
    knots = max(2, round(length * _KNOTS_PER_FRAME) + 1)
    values = np.clip(rng.standard_normal((knots, len(UPPER_BONES), 3)), -2.5, 2.5) * np.radians(sigma_deg / np.sqrt(3))
    at = np.linspace(0.0, max(length - 1, 1), knots)
    return CubicSpline(at, values, axis=0, bc_type="natural")(np.arange(length)).astype(np.float64)


def bend(positions: np.ndarray, rotvecs: np.ndarray) -> np.ndarray:
    """``positions`` [T, 18, 3] with each upper-body bone rotated about its parent joint by ``rotvecs`` [T, U, 3]
    (from :func:`draw_bend`), each rotation carried down to the bones below it; the legs and root unchanged.
    Returns [T, 18, 3] float32."""
    pos = np.asarray(positions, dtype=np.float64)
    t = len(pos)
    if rotvecs.shape != (t, len(UPPER_BONES), 3):
        raise ValueError(f"rotvecs must be [{t}, {len(UPPER_BONES)}, 3], got {rotvecs.shape}")
    vectors = bone_vectors(pos)  # [T, 17, 3]
    own = Rotation.from_rotvec(rotvecs.reshape(-1, 3)).as_matrix().reshape(t, len(UPPER_BONES), 3, 3)
    total: dict[int, np.ndarray] = {}
    for k, b in enumerate(UPPER_BONES):  # parents come before children in BONES
        parent = int(_PARENT_BONE[b])
        total[b] = own[:, k] if parent not in total else total[parent] @ own[:, k]
        vectors[:, b] = np.einsum("tij,tj->ti", total[b], vectors[:, b])
    return assemble(pos[:, _ROOT], vectors).astype(np.float32)


__all__ = ["UPPER_BONES", "bend", "draw_bend", "splice"]
