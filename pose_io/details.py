"""The details of a pose beyond body15 (face, hands, feet of :data:`pose_io.layouts.BODY31`): carried from one
body onto another, and which way a body faces.

Retargeting moves body15 only. :func:`carry_details` puts each detail point of the driver on the retargeted body
through its parent bone: the similarity (rotation and scale) that takes the driver's bone onto the driven bone takes
the point with it, so the head turns and the hands open as the driver's do, at the size of the body they now sit
on. Face points ride the neck-nose bone, hand points the elbow-wrist bone, foot points the knee-ankle bone.
"""

from __future__ import annotations

import numpy as np

from pose_io.layouts import BODY15, BODY31, JointLayout

# Detail joint -> (bone start, bone end): the bone it moves with; the point is placed relative to the end.
PARENT_BONES: dict[str, tuple[str, str]] = {
    **{n: ("neck", "nose") for n in ("r_eye", "l_eye", "r_ear", "l_ear", "mouth_right", "mouth_left")},
    **{f"{s}_{n}": (f"{s}_elbow", f"{s}_wrist") for s in "rl" for n in ("thumb", "index", "pinky")},
    **{f"{s}_{n}": (f"{s}_knee", f"{s}_ankle") for s in "rl" for n in ("heel", "big_toe")},
}


def carry_details(body: np.ndarray, source: np.ndarray, layout: JointLayout = BODY31) -> np.ndarray:
    """Driven body15 joints with the driver's detail points carried onto them.

    Args:
        body: [T, 15, 2] body15 joints of the driven body (NaN where missing).
        source: [T, J, 2] the driver's joints in ``layout`` (body15 joints first, then details; NaN where missing).
        layout: the detailed layout (default body31).

    Returns:
        [T, J, 2] float32: ``body`` followed by the carried details; a detail is missing where it, its parent
        bone in the driver or that bone in the driven body is missing, or a bone has no length.
    """
    t = len(body)
    out = np.full((t, len(layout), 2), np.nan, dtype=np.float32)
    out[:, : len(BODY15)] = body
    for name, (a_name, b_name) in PARENT_BONES.items():
        if not layout.has(name):
            continue
        a, b, j = BODY15.index(a_name), BODY15.index(b_name), layout.index(name)
        src_bone = source[:, b] - source[:, a]  # [T, 2]
        dst_bone = body[:, b] - body[:, a]
        # The complex ratio dst / src is the similarity from one bone onto the other.
        src_c = src_bone[:, 0] + 1j * src_bone[:, 1]
        dst_c = dst_bone[:, 0] + 1j * dst_bone[:, 1]
        with np.errstate(invalid="ignore", divide="ignore"):
            ratio = np.where(np.abs(src_c) > 1e-6, dst_c / src_c, np.nan)
        offset = (source[:, j, 0] - source[:, b, 0]) + 1j * (source[:, j, 1] - source[:, b, 1])
        placed = body[:, b, 0] + 1j * body[:, b, 1] + ratio * offset
        out[:, j, 0], out[:, j, 1] = placed.real, placed.imag
    bad = ~np.isfinite(out).all(axis=-1)
    out[bad] = np.nan
    return out


def facing(joints: np.ndarray, layout: JointLayout) -> np.ndarray:
    """[...] how much a body faces the camera, in [-1, 1], from [..., J, 2] image joints (y down).

    +1: the chest faces the camera (the body's left shoulder and hip on the image's right), -1: its back, 0: seen
    from the side or unknown. The signed width of the shoulders and of the hips over the trunk's length, each
    clipped at half of it (a frontal trunk is about 0.6 of its length wide).
    """
    def width(left: str, right: str) -> np.ndarray:
        return joints[..., layout.index(left), 0] - joints[..., layout.index(right), 0]

    trunk = np.linalg.norm(joints[..., layout.index("neck"), :] - joints[..., layout.index("mid_hip"), :], axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        parts = np.stack([width("l_shoulder", "r_shoulder"), width("l_hip", "r_hip")], axis=-1) / (
            0.5 * trunk[..., None])
    clipped = np.clip(parts, -1.0, 1.0)
    known = np.isfinite(clipped)
    score = np.where(known, clipped, 0.0).sum(axis=-1) / np.maximum(known.sum(axis=-1), 1)
    return score.astype(np.float32)


__all__ = ["PARENT_BONES", "carry_details", "facing"]
