"""Weak-perspective cameras for the motion world, the view bins and the one framing rule.

Angles are relative to the character: the view yaw is measured from the direction the character faces
on average (``facing_angle``), as in Aberman et al. 2019. Yaw 0 sees the face, +90 the character's own
left side (the character then faces image left), -90 its right side. Positive pitch puts the camera
above the character, looking down.

Projection (``project``): rotate world points about the origin by the facing and the view, then
``x = tx + scale * X``, ``y = ty - scale * Y`` (pixels, x right, y down) and ``depth = -Z`` (metres,
larger = farther from the camera). A ``Motion3D`` has its first root over the origin on the ground, so
``(tx, ty)`` is where the ground under the clip's first root lands.

Framing rule (``frame_camera``), used for training data, the renderer and evaluation alike: on a
W x H canvas the ground point under the first root is at ``(W / 2, 0.9 H)`` and the scale is
``0.36 H`` pixels per metre (a 1.75 m person is 323 px tall on a 512 px canvas). Rendering the reference
character with the driver's motion through ``frame_camera(yaw, pitch, size)`` is therefore exactly the
ground truth of a cloning run.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from retarget.world.skeleton import Motion3D, joint_index

FRAME_GROUND = 0.90
FRAME_SCALE = 0.36
CANVAS_SIZE = (512, 512)

# Discrete views for the triplet loss: 13 yaw bins of 15 degrees from -90 to +90.
VIEW_YAWS: tuple[float, ...] = tuple(float(v) for v in range(-90, 91, 15))
MAX_PITCH = 10.0
# Views a person is mostly seen from in videos (dance, fitness, talks): within this yaw of the front.
FRONTAL_YAW = 45.0
# Perspective cameras aim at this height (metres) above the ground under the clip's first root.
AIM_HEIGHT = 1.0


@dataclass(frozen=True)
class Camera:
    """A weak-perspective camera.

    Attributes:
        yaw_deg: view angle around the character relative to its facing (0 = front, +90 = its left).
        pitch_deg: elevation (+ = from above, looking down).
        roll_deg: rotation of the image about the view axis (+ = counter-clockwise on screen).
        scale: pixels per metre.
        tx: pixel x of the origin (the ground under the clip's first root).
        ty: pixel y of the origin: the ground line.
    """

    yaw_deg: float = 0.0
    pitch_deg: float = 0.0
    roll_deg: float = 0.0
    scale: float = FRAME_SCALE * CANVAS_SIZE[1]
    tx: float = CANVAS_SIZE[0] / 2
    ty: float = FRAME_GROUND * CANVAS_SIZE[1]

    def rotation(self, facing_deg: float = 0.0) -> np.ndarray:
        """[3, 3] world -> camera rotation: ``Rz(roll) @ Rx(pitch) @ Ry(-(yaw + facing))``."""
        return view_rotation(self.yaw_deg + facing_deg, self.pitch_deg, self.roll_deg)


@dataclass(frozen=True)
class CameraSpread:
    """How the random camera of a window is drawn (defaults: the world's own, pitch only).

    Real videos are shot from above or below and from a few metres away, so a near body part looks bigger
    than a far one; the world's cameras are weak-perspective and nearly level. Training can widen both.

    Attributes:
        max_pitch: pitch uniform in +-``max_pitch`` degrees.
        perspective: share of cameras at a finite distance (perspective); the others are weak-perspective.
        near: closest distance (metres) of a perspective camera from the nearest joint of its window.
        far: farthest such distance; uniform in [near, far].
    """

    max_pitch: float = MAX_PITCH
    perspective: float = 0.0
    near: float = 2.0
    far: float = 8.0

    def __post_init__(self) -> None:
        if not 0 <= self.max_pitch < 90:
            raise ValueError("max_pitch must be in [0, 90) degrees")
        if not 0 <= self.perspective <= 1:
            raise ValueError("perspective must be a share in [0, 1]")
        if not 0.5 <= self.near <= self.far <= 1000:
            raise ValueError("camera distances must be 0.5 <= near <= far <= 1000 metres")

    def draw(self, rng: np.random.Generator, count: int) -> tuple[np.ndarray, np.ndarray]:
        """[count] pitches (degrees) and [count] distances (metres; inf = weak perspective).

        With ``perspective`` 0 only the pitches are drawn, so the default consumes ``rng`` exactly as the
        world's cameras always have.
        """
        pitch = rng.uniform(-self.max_pitch, self.max_pitch, size=count)
        distance = np.full(count, np.inf)
        if self.perspective > 0:
            near = rng.random(count) < self.perspective
            drawn = rng.uniform(self.near, self.far, size=count)
            distance[near] = drawn[near]
        return pitch, distance


WORLD_CAMERAS = CameraSpread()


def perspective_xy(cam: np.ndarray, aim: np.ndarray, distance: np.ndarray) -> np.ndarray:
    """Camera-frame points seen in perspective: [B, L, J, 3] metres -> [B, L, J, 2] metres (x, y up).

    Each window's camera looks at its ``aim`` point; a point at the aim's depth keeps its weak-perspective
    position, nearer points are magnified and farther ones shrunk. ``distance`` is how far the camera is
    from the window's nearest point (so a clip walking towards the camera never reaches it); inf gives the
    weak-perspective projection unchanged.

    Args:
        cam: [B, L, J, 3] rotated points, +z towards the camera.
        aim: [B, 3] the rotated aim point of each window.
        distance: [B] metres (inf = weak perspective).
    """
    rel = cam - aim[:, None, None, :]  # [B, L, J, 3]
    out = cam[..., :2].copy()
    finite = np.isfinite(distance)
    if finite.any():
        r = rel[finite]
        nearest = np.maximum(r[..., 2].reshape(len(r), -1).max(axis=1), 0.0)  # [b] metres in front of the aim
        d = (np.asarray(distance, np.float64)[finite] + nearest)[:, None, None]  # camera to aim depth
        factor = d / (d - r[..., 2])  # [b, L, J], >= 1 for points nearer than the aim
        out[finite] = aim[finite][:, None, None, :2] + r[..., :2] * factor[..., None]
    return out


def view_rotation(yaw_deg: float, pitch_deg: float = 0.0, roll_deg: float = 0.0) -> np.ndarray:
    """[3, 3] rotation taking the camera direction (yaw about Y from +Z, pitch up) to +Z."""
    return view_rotations(np.array([yaw_deg]), np.array([pitch_deg]), np.array([roll_deg]))[0]


def view_rotations(yaw_deg: np.ndarray, pitch_deg: np.ndarray, roll_deg: np.ndarray | None = None) -> np.ndarray:
    """[B, 3, 3] ``Rz(roll) @ Rx(pitch) @ Ry(-yaw)`` for [B] angles in degrees."""
    y = np.radians(np.asarray(yaw_deg, dtype=np.float64))
    p = np.radians(np.asarray(pitch_deg, dtype=np.float64))
    r = np.zeros_like(y) if roll_deg is None else np.radians(np.asarray(roll_deg, dtype=np.float64))
    cy, sy, cp, sp, cr, sr = np.cos(y), np.sin(y), np.cos(p), np.sin(p), np.cos(r), np.sin(r)
    zero, one = np.zeros_like(y), np.ones_like(y)
    ry = np.stack([cy, zero, -sy, zero, one, zero, sy, zero, cy], axis=-1).reshape(-1, 3, 3)  # Ry(-yaw)
    rx = np.stack([one, zero, zero, zero, cp, -sp, zero, sp, cp], axis=-1).reshape(-1, 3, 3)
    rz = np.stack([cr, -sr, zero, sr, cr, zero, zero, zero, one], axis=-1).reshape(-1, 3, 3)
    return rz @ rx @ ry


def frame_camera(
    yaw_deg: float, pitch_deg: float = 0.0, size: tuple[int, int] = CANVAS_SIZE, roll_deg: float = 0.0
) -> Camera:
    """The framing rule: ground under the first root at (W/2, 0.9 H), 0.36 H pixels per metre.

    Args:
        yaw_deg: view yaw relative to the character's facing.
        pitch_deg: camera elevation.
        size: canvas (width, height) in pixels.
        roll_deg: image roll.
    """
    w, h = size
    return Camera(yaw_deg, pitch_deg, roll_deg, scale=FRAME_SCALE * h, tx=w / 2.0, ty=FRAME_GROUND * h)


_ACROSS = np.array([joint_index(n) for n in ("l_hip", "r_hip", "l_shoulder", "r_shoulder")])


def facing_vectors(positions: np.ndarray) -> np.ndarray:
    """[..., T, 2] unit (x, z) facing direction per frame, from the hips' and shoulders' left-right axis.

    Args:
        positions: [..., T, 18, 3] world joints (Y up).
    """
    p = np.asarray(positions, dtype=np.float64)[..., _ACROSS, :]  # [..., T, 4, 3]
    left = p[..., 0, :] - p[..., 1, :] + p[..., 2, :] - p[..., 3, :]
    # forward = left x up, with up = +Y: (-left_z, 0, left_x).
    fwd = np.stack([-left[..., 2], left[..., 0]], axis=-1)
    norm = np.linalg.norm(fwd, axis=-1, keepdims=True)
    return fwd / np.maximum(norm, 1e-9)


def facing_angle(motion: Motion3D | np.ndarray) -> float:
    """The character's average facing over the clip, in degrees about +Y (0 = facing +Z, 90 = +X).

    Args:
        motion: a ``Motion3D`` or its [T, 18, 3] positions.
    """
    pos = motion.positions if isinstance(motion, Motion3D) else np.asarray(motion)
    return float(facing_angles(pos))


def facing_angles(positions: np.ndarray) -> np.ndarray:
    """[...] average facing in degrees of [..., T, 18, 3] clips (batched ``facing_angle``)."""
    fwd = facing_vectors(positions).mean(axis=-2)
    return np.degrees(np.arctan2(fwd[..., 0], fwd[..., 1]))


def project(
    positions: np.ndarray,
    camera: Camera,
    facing_deg: float = 0.0,
    origin: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Weak-perspective projection.

    Args:
        positions: [..., 3] world points in metres (Y up), e.g. [T, K, 3].
        camera: the camera.
        facing_deg: the character's facing (``facing_angle``); the view yaw is added to it.
        origin: [3] world point that lands on ``(tx, ty)``; default the world origin (the ground under
            a ``Motion3D``'s first root).

    Returns:
        ``(xy [..., 2] float32 pixels x right y down, depth [...] float32 metres, larger = farther)``.
    """
    pts = np.asarray(positions, dtype=np.float64)
    if origin is not None:
        pts = pts - np.asarray(origin, dtype=np.float64)
    cam = pts @ camera.rotation(facing_deg).T  # [..., 3] camera coordinates, Y up, +Z toward the camera
    xy = np.stack([camera.tx + camera.scale * cam[..., 0], camera.ty - camera.scale * cam[..., 1]], axis=-1)
    return xy.astype(np.float32), (-cam[..., 2]).astype(np.float32)


def ground_origin(positions: np.ndarray) -> np.ndarray:
    """[3] the ground point (y = 0) under the first frame's root of [T, 18, 3] positions."""
    root = np.asarray(positions[0, joint_index("mid_hip")], dtype=np.float64)
    return np.array([root[0], 0.0, root[2]])


__all__ = [
    "CANVAS_SIZE",
    "FRAME_GROUND",
    "FRAME_SCALE",
    "FRONTAL_YAW",
    "MAX_PITCH",
    "VIEW_YAWS",
    "Camera",
    "facing_angle",
    "facing_angles",
    "facing_vectors",
    "frame_camera",
    "ground_origin",
    "project",
    "view_rotation",
    "view_rotations",
]
