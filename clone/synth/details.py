"""The detail points of a synthetic performer: eyes, ears, mouth corners, hands and heels where the renderer
draws them, so that a rendered performance has the detailed (body31) pose track MediaPipe gives of a real video.

The points are placed on the primitives :class:`~clone.synth.body.PerformerRenderer` draws: the eyes and the
mouth where the head's face side paints them, the ears on the head's sides, thumb,
index and pinky on the hand's capsule past the wrist (the thumb towards the chest's front), the heel behind the
ankle along the foot. Like MediaPipe's landmarks they are given whether or not they face the camera (a back view
has its eyes projected onto the back of the head, left and right swapped as they appear).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from clone.synth.appearance import BodyShape
from pose_io.layouts import get_layout
from pose_io.track import PoseTrack


def _unit(v: np.ndarray) -> np.ndarray:
    """[..., 3] vectors scaled to length 1 (zero vectors stay zero)."""
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.divide(v, n, out=np.zeros_like(v), where=n > 1e-9)


def head_axes(centre: np.ndarray, neck: np.ndarray, nose: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The head's (face, up, side) unit vectors from [..., 3] skull centre, neck and nose, as the renderer turns it:
    up from the neck to the skull's centre, face towards the nose square to up, side = up x face (the
    performer's left)."""
    up = _unit(centre - neck)
    face = nose - centre
    face = _unit(face - up * np.sum(face * up, axis=-1, keepdims=True))
    return face, up, np.cross(up, face)


def chest_forward(p: dict[str, np.ndarray]) -> np.ndarray:
    """[..., 3] unit vector the chest faces (shoulder and hip lines x spine, signed by the nose)."""
    left = p["l_shoulder"] - p["r_shoulder"] + p["l_hip"] - p["r_hip"]
    spine = 0.5 * (p["l_shoulder"] + p["r_shoulder"] - p["l_hip"] - p["r_hip"])
    forward = _unit(np.cross(left, spine))
    flip = np.sum(forward * (p["nose"] - p["neck"]), axis=-1, keepdims=True) < 0
    return np.where(flip, -forward, forward)


def detail_points(p3: np.ndarray, joint_names: Sequence[str], shape: BodyShape) -> dict[str, np.ndarray]:
    """The detail points of projected joints.

    Args:
        p3: [T, K, 3] joints in metres in camera coordinates (x right, y down, z away), NaN where missing.
        joint_names: the K names (the motion world's joints).
        shape: the performer's body shape (head radius, hand and heel sizes).

    Returns:
        name -> [T, 3] for the eyes, ears, mouth corners, thumbs, index fingers, pinkies and heels (NaN where
        a joint they hang from is missing).
    """
    p = {n: p3[:, k] for k, n in enumerate(joint_names)}
    face, up, side = head_axes(p["head"], p["neck"], p["nose"])
    hr = shape.head_radius
    # The head is a capsule of radius hr from the chin to the crown (as the renderer draws it); a point of the
    # face with normal n lies hr along n from the crown's sphere (n up) or the chin's (n down).
    crown, chin = p["head"] + up * (0.2 * hr), p["head"] - up * (0.45 * hr)
    out: dict[str, np.ndarray] = {}
    for name, s in (("l", 1.0), ("r", -1.0)):
        out[f"{name}_eye"] = crown + hr * _unit(face * 0.86 + up * 0.16 + side * (0.42 * s))
        out[f"{name}_ear"] = p["head"] + hr * (side * s - up * 0.1)
    out["mouth_left"] = chin + hr * _unit(face * 0.89 - up * 0.4 + side * 0.18)
    out["mouth_right"] = chin + hr * _unit(face * 0.89 - up * 0.4 - side * 0.18)
    forward = chest_forward(p)
    for s in ("l", "r"):
        wrist = p[f"{s}_wrist"]
        along = _unit(wrist - p[f"{s}_elbow"])
        # the hand's front (thumb side): the chest's forward direction square to the forearm
        front = _unit(forward - along * np.sum(forward * along, axis=-1, keepdims=True))
        length, radius = shape.hand_length, shape.hand_radius
        out[f"{s}_index"] = wrist + along * length + front * (0.5 * radius)
        out[f"{s}_pinky"] = wrist + along * (0.85 * length) - front * (0.6 * radius)
        out[f"{s}_thumb"] = wrist + along * (0.45 * length) + front * (1.2 * radius)
        toe, ankle = p[f"{s}_big_toe"], p[f"{s}_ankle"]
        out[f"{s}_heel"] = ankle - _unit(toe - ankle) * shape.heel
    return out


def detail_track(xy: np.ndarray, depth: np.ndarray, px_per_m: float, joint_names: Sequence[str], shape: BodyShape,
                 fps: float, size: tuple[int, int]) -> PoseTrack:
    """The body31 track of a rendered performance: its joints and their :func:`detail_points`, in pixels.

    Args:
        xy: [T, K, 2] pixel coordinates of the joints (NaN where missing).
        depth: [T, K] metres, larger is farther.
        px_per_m: the camera's pixels per metre (weak perspective: pixel = metres x px_per_m).
        joint_names: the K names.
        shape: the performer's body shape.
        fps: frame rate.
        size: (width, height) of the canvas.
    """
    p3 = np.concatenate([np.asarray(xy, np.float64) / px_per_m, np.asarray(depth, np.float64)[..., None]], axis=-1)
    points = {n: p3[:, k] for k, n in enumerate(joint_names)}
    points.update(detail_points(p3, joint_names, shape))
    layout = get_layout("body31")
    joints = np.full((p3.shape[0], len(layout), 2), np.nan, dtype=np.float32)
    for name in layout.joints:
        if name in points:
            joints[:, layout.index(name)] = points[name][:, :2] * px_per_m
    conf = np.where(np.isnan(joints[..., 0]), 0.0, 1.0).astype(np.float32)
    return PoseTrack(joints, conf, fps, size, layout.name)
