"""Pose maps with details (the ``body31`` layout): body15 as before, plus the hands and feet, and a head that
tells front from back.

A body15 pose map looks nearly alike from the front and from the back, and the generator then paints hair and
face at once where the reference turns. Here the face's features (eyes, nose-eye lines, mouth) are drawn only as
far as the trunk faces the camera (:func:`pose_io.details.facing`, from the shoulders' and hips' order on
screen, which the retargeted body keeps), and the back of the head as a filled grey disc as far as it turns
away; the ears are drawn either way. Hands (thumb, index, pinky) and feet (heel, big toe) are drawn whenever
they are known. Detail points that a track lacks (BODY_25 has no mouth or hands) are simply not drawn.
"""

from __future__ import annotations

from functools import lru_cache

import cv2
import numpy as np

from pose_io.details import facing
from pose_io.draw import draw_pose
from pose_io.layouts import BODY15, BODY31, JointLayout

_FACE = ("nose", "r_eye", "l_eye", "mouth_right", "mouth_left")
_EARS = ("r_ear", "l_ear")
_LIMBS = ("r_thumb", "r_index", "r_pinky", "l_thumb", "l_index", "l_pinky", "r_heel", "r_big_toe", "l_heel",
          "l_big_toe")
_FACE_IDX = BODY31.indices(list(_FACE))
_EAR_IDX = BODY31.indices(list(_EARS))
_LIMB_IDX = BODY31.indices(list(_LIMBS))
_PARENT = {n: f"{n[0]}_{'wrist' if n[2:] in ('thumb', 'index', 'pinky') else 'ankle'}" for n in _LIMBS}
_BACK_OF_HEAD = np.array([150, 150, 150])
_LEVELS = 8  # face and back-of-head intensities are drawn in this many steps


def _part_layout(name: str, limbs: tuple[tuple[str, str], ...], weight: float = 1.0) -> JointLayout:
    colors = tuple(tuple(round(c * weight) for c in rgb) for rgb in BODY31.colors)
    return JointLayout(name=name, joints=BODY31.joints, limbs=limbs, colors=colors)


_HANDS_FEET = _part_layout("body31-hands-feet", tuple(lb for lb in BODY31.limbs if lb[1] in _LIMBS))
_EAR_LAYOUT = _part_layout("body31-ears", ())


@lru_cache(maxsize=_LEVELS + 1)
def _face_layout(level: int) -> JointLayout:
    limbs = tuple(lb for lb in BODY31.limbs if lb[0] in _FACE and lb[1] in _FACE)
    return _part_layout(f"body31-face-{level}", limbs, level / _LEVELS)


def _only(joints: np.ndarray, keep: list[int]) -> np.ndarray:
    out = np.full_like(joints, np.nan)
    out[keep] = joints[keep]
    return out


def render_detail_map(joints: np.ndarray, canvas: np.ndarray, thickness: int) -> np.ndarray:
    """Draw a body31 pose onto ``canvas`` (in place) and return it.

    Args:
        joints: [31, 2] canvas pixels, NaN where missing.
        canvas: [S, S, 3] uint8 RGB (black).
        thickness: limb width in pixels.
    """
    body = joints[: len(BODY15)]
    toward = float(facing(body, BODY15))
    head, neck = body[BODY15.index("nose")], body[BODY15.index("neck")]
    away = min(max(-2.0 * toward, 0.0), 1.0)
    if away > 0 and np.isfinite(head).all() and np.isfinite(neck).all():
        radius = 0.55 * float(np.linalg.norm(head - neck))
        color = tuple(int(v) for v in np.round(_BACK_OF_HEAD * round(away * _LEVELS) / _LEVELS))
        cv2.circle(canvas, tuple(round(v * 16) for v in head), round(radius * 16), color, -1,
                   cv2.LINE_AA, 4)
    draw_pose(canvas, body, BODY15, thickness=thickness)
    # Hand and foot points with the wrist or ankle they hang from (only where one of them is known: a track
    # without details draws as body15 does).
    known = [i for i in _LIMB_IDX if np.isfinite(joints[i]).all()]
    parents = sorted({BODY31.index(_PARENT[BODY31.joints[i]]) for i in known})
    draw_pose(canvas, _only(joints, known + parents), _HANDS_FEET, thickness=max(1, (thickness + 1) // 2))
    draw_pose(canvas, _only(joints, _EAR_IDX), _EAR_LAYOUT, thickness=thickness)
    level = round(min(max(2.0 * toward, 0.0), 1.0) * _LEVELS)
    if level > 0:
        draw_pose(canvas, _only(joints, _FACE_IDX), _face_layout(level), thickness=max(1, (thickness + 1) // 2))
    return canvas


__all__ = ["render_detail_map"]
