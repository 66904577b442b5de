"""A humanoid BVH the tests write themselves: one rig under several namings, standing or walking.

Used by the rig tests (namings, units, up axis) and by the motion-world tests, which need a few clips
with real motion but not the mocap of ../shared.
"""

from __future__ import annotations

import gzip
import math
from pathlib import Path

ROLES = {  # role -> (parent role, offset in cm, Y up, facing +Z, left = +X)
    "hips": (None, (0, 95, 0)),
    "spine": ("hips", (0, 10, 0)), "neck": ("spine", (0, 40, 0)), "head": ("neck", (0, 10, 0)),
    "l_collar": ("spine", (3, 36, 0)), "l_shoulder": ("l_collar", (14, 0, 0)), "l_elbow": ("l_shoulder", (0, -30, 0)),
    "l_wrist": ("l_elbow", (0, -25, 0)),
    "r_collar": ("spine", (-3, 36, 0)), "r_shoulder": ("r_collar", (-14, 0, 0)), "r_elbow": ("r_shoulder", (0, -30, 0)),
    "r_wrist": ("r_elbow", (0, -25, 0)),
    "l_hip": ("hips", (9, -5, 0)), "l_knee": ("l_hip", (0, -42, 0)), "l_ankle": ("l_knee", (0, -41, 0)),
    "l_toe": ("l_ankle", (0, -6, 14)),
    "r_hip": ("hips", (-9, -5, 0)), "r_knee": ("r_hip", (0, -42, 0)), "r_ankle": ("r_knee", (0, -41, 0)),
    "r_toe": ("r_ankle", (0, -6, 14)),
}


def _swing_degrees(role: str, phase: float, swing: float, bow: float) -> float:
    """X rotation (forward/back in the facing direction) of ``role`` at stride ``phase`` (radians)."""
    side = 1.0 if role.startswith("l_") else -1.0
    s = math.sin(phase)
    if role in ("l_hip", "r_hip"):
        return -side * swing * s
    if role in ("l_knee", "r_knee"):
        return swing * max(0.0, side * s)  # the knee bends while its leg swings back
    if role in ("l_shoulder", "r_shoulder"):
        return side * 0.8 * swing * s
    if role in ("l_elbow", "r_elbow"):
        return -0.3 * swing
    if role == "spine":
        return bow * (1 - math.cos(phase)) / 2
    return 0.0


def humanoid_bvh(
    names: dict[str, str],
    scale: float = 1.0,
    frames: int = 4,
    step: float = 5.0,
    swing: float = 0.0,
    bow: float = 0.0,
    period: float = 30.0,
    frame_time: float = 0.0333333,
) -> str:
    """A BVH of the humanoid above (names per role) moving forward ``step`` cm a frame.

    Args:
        names: the rig's bone name of every role.
        scale: file units per cm (0.01: metres).
        frames: clip length.
        step: forward travel per frame in cm.
        swing: amplitude in degrees of the legs' and arms' swing (0: a rigid figure gliding).
        bow: how far in degrees the spine bends forward at the middle of each period.
        period: frames per stride.
        frame_time: seconds per frame.
    """
    children: dict[str | None, list[str]] = {}
    for role, (parent, _) in ROLES.items():
        children.setdefault(parent, []).append(role)
    lines = ["HIERARCHY"]
    order: list[str] = []

    def emit(role: str, depth: int) -> None:
        pad = "  " * depth
        order.append(role)
        off = " ".join(f"{v * scale:g}" for v in ROLES[role][1])
        lines.append(f"{pad}{'ROOT' if depth == 0 else 'JOINT'} {names[role]}")
        lines.append(pad + "{")
        lines.append(f"{pad}  OFFSET {off}")
        chans = "6 Xposition Yposition Zposition Zrotation Xrotation Yrotation" if depth == 0 else "3 Zrotation Xrotation Yrotation"
        lines.append(f"{pad}  CHANNELS {chans}")
        kids = children.get(role, [])
        for kid in kids:
            emit(kid, depth + 1)
        if not kids:
            lines.extend([f"{pad}  End Site", pad + "  {", f"{pad}    OFFSET 0 {5 * scale:g} 0", pad + "  }"])
        lines.append(pad + "}")

    emit("hips", 0)
    lines += ["MOTION", f"Frames: {frames}", f"Frame Time: {frame_time:g}"]
    for t in range(frames):
        phase = 2 * math.pi * t / period
        vals = [0.0, 95 * scale, step * t * scale, 0, 0, 0]
        for role in order[1:]:
            vals += [0.0, _swing_degrees(role, phase, swing, bow), 0.0]
        lines.append(" ".join(f"{v:g}" for v in vals))
    return "\n".join(lines) + "\n"


MOTIONBUILDER = {
    "hips": "Hips", "spine": "Spine", "neck": "Neck", "head": "Head", "l_collar": "LeftShoulder",
    "l_shoulder": "LeftArm", "l_elbow": "LeftForeArm", "l_wrist": "LeftHand", "l_hip": "LeftUpLeg",
    "l_knee": "LeftLeg", "l_ankle": "LeftFoot", "l_toe": "LeftToeBase",
}
MOTIONBUILDER.update({k.replace("l_", "r_"): v.replace("Left", "Right") for k, v in MOTIONBUILDER.items() if k.startswith("l_")})
MAX3DS = {
    "hips": "Hips", "spine": "Chest", "neck": "Neck", "head": "Head", "l_collar": "LeftCollar",
    "l_shoulder": "LeftShoulder", "l_elbow": "LeftElbow", "l_wrist": "LeftWrist", "l_hip": "LeftHip",
    "l_knee": "LeftKnee", "l_ankle": "LeftAnkle", "l_toe": "LeftToe",
}
MAX3DS.update({k.replace("l_", "r_"): v.replace("Left", "Right") for k, v in MAX3DS.items() if k.startswith("l_")})
BANDAI_NAMCO = {
    "hips": "Hips", "spine": "Chest", "neck": "Neck", "head": "Head", "l_collar": "Shoulder_L",
    "l_shoulder": "UpperArm_L", "l_elbow": "LowerArm_L", "l_wrist": "Hand_L", "l_hip": "UpperLeg_L",
    "l_knee": "LowerLeg_L", "l_ankle": "Foot_L", "l_toe": "Toes_L", "r_collar": "Shoulder_R",
    "r_shoulder": "UpperArm_R", "r_elbow": "LowerArm_R", "r_wrist": "Hand_R", "r_hip": "UpperLeg_R",
    "r_knee": "LowerLeg_R", "r_ankle": "Foot_R", "r_toe": "Toes_R",
}


def write_clip(path: Path, frames: int = 130) -> Path:
    """A gzipped Bandai-Namco-named clip of the motion its file name says, e.g. ``dataset-1_walk_normal_002.bvh.gz``.

    ``bow`` in the name: bowing on the spot; anything else: walking, a little faster and with a longer stride
    for a higher take number, so two takes of one motion differ.
    """
    name = Path(path).name
    bow = "bow" in name
    take = int(name.split("_")[-1].split(".")[0])
    text = humanoid_bvh(BANDAI_NAMCO, frames=frames, step=0.0 if bow else 4.0 + take, swing=0.0 if bow else 25.0,
                        bow=50.0 if bow else 0.0, period=40.0 if bow else 28.0 + 2 * take)
    Path(path).write_bytes(gzip.compress(text.encode()))
    return Path(path)
