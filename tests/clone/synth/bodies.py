"""Tiny bodies for the renderer's tests: a standing adult, an arm wave, an orthographic view."""

from __future__ import annotations

import numpy as np

from clone.synth import Look, PerformerRenderer, get_look, make_background
from retarget.world.skeleton import WORLD_JOINTS, Motion3D, normalise_placement

SIZE = 128
SCALE = 0.4 * SIZE  # pixels per metre

# A standing adult (metres, Y up, facing +Z), by world joint name.
STANDING = {
    "head": (0.0, 1.62, 0.0), "nose": (0.0, 1.58, 0.1), "neck": (0.0, 1.42, 0.0),
    "r_shoulder": (-0.19, 1.42, 0.0), "l_shoulder": (0.19, 1.42, 0.0),
    "r_elbow": (-0.24, 1.14, -0.02), "l_elbow": (0.24, 1.14, 0.0),
    "r_wrist": (-0.30, 0.90, 0.1), "l_wrist": (0.27, 0.88, 0.03),
    "mid_hip": (0.0, 0.95, 0.0), "r_hip": (-0.1, 0.95, 0.0), "l_hip": (0.1, 0.95, 0.0),
    "r_knee": (-0.11, 0.52, 0.06), "l_knee": (0.1, 0.52, 0.02),
    "r_ankle": (-0.12, 0.09, -0.02), "l_ankle": (0.1, 0.09, -0.02),
    "r_big_toe": (-0.14, 0.02, 0.15), "l_big_toe": (0.12, 0.02, 0.15),
}


def standing() -> np.ndarray:
    """[18, 3] the standing body in ``WORLD_JOINTS`` order."""
    return np.array([STANDING[n] for n in WORLD_JOINTS], dtype=np.float64)


def project(points: np.ndarray, yaw_deg: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Turn [..., 3] points by ``yaw`` about Y, project orthographically: (xy [..., 2] px, depth [...] m)."""
    a = np.deg2rad(yaw_deg)
    rot = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
    p = points @ rot.T
    xy = np.stack([SIZE / 2 + SCALE * p[..., 0], 0.92 * SIZE - SCALE * p[..., 1]], axis=-1)
    return xy, 5.0 - p[..., 2]


def waving(frames: int) -> np.ndarray:
    """[T, 18, 3] the standing body raising its right arm sideways."""
    out = np.repeat(standing()[None], frames, axis=0)
    sh = out[:, WORLD_JOINTS.index("r_shoulder")]
    for t in range(frames):
        angle = np.deg2rad(20 + 110 * t / max(frames - 1, 1))
        arm = np.array([-np.sin(angle), -np.cos(angle), 0.0])
        out[t, WORLD_JOINTS.index("r_elbow")] = sh[t] + 0.3 * arm
        out[t, WORLD_JOINTS.index("r_wrist")] = sh[t] + 0.55 * arm
    return out


def renderer(look: Look | None = None) -> tuple[PerformerRenderer, np.ndarray]:
    """A renderer of ``look`` (default: ``average``) on a SIZE² canvas, and its background."""
    look = look or get_look("average")
    background = make_background(SIZE, SIZE, look.backdrop, 0.8 * SIZE)
    return PerformerRenderer(look, background, WORLD_JOINTS), background


def motion_of(positions: np.ndarray) -> Motion3D:
    """A 30 fps motion of [T, 18, 3] world positions."""
    return Motion3D(normalise_placement(positions).astype(np.float32), 30.0, "wave")
