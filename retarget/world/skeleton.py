"""The canonical 3D skeleton of the motion world: joints, bones, skeletons and 3D retargeting (the characters
themselves: :mod:`retarget.world.characters`).

World coordinates are metres, Y up, right-handed. A ``Motion3D`` is normalised so that the ground is
``y = 0`` (where the lowest foot joint rests) and the clip's first root (``mid_hip``) stands over the
origin; ``camera.project`` relies on that.

A character is a ``Skeleton``: one length per bone of a fixed tree over ``WORLD_JOINTS``. Retargeting a
motion onto a character keeps every bone's direction in every frame and changes its length, which is
what replaying the joint rotations on rescaled rig offsets does; the root path is scaled with the legs
and the feet are kept on the ground.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from pose_io.layouts import BODY15

# The 15 body joints of OpenPose's BODY_25 head, then the big toes and the centre of the skull. ``nose``
# is a point in front of the face, ``neck`` the shoulders' midpoint, ``mid_hip`` the hips' midpoint.
WORLD_JOINTS: tuple[str, ...] = BODY15.joints + ("l_big_toe", "r_big_toe", "head")
_J = {name: i for i, name in enumerate(WORLD_JOINTS)}

# The canonical tree, parents before children. A bone is named after its child joint: "l_knee" is the
# left thigh, "neck" the torso (mid_hip -> shoulders' midpoint), "head" the neck (-> centre of the skull),
# "nose" the face (skull centre -> nose), "l_shoulder" half the shoulder width, "l_hip" half the hip width.
# It is not a second copy of a mocap rig's tree (``retarget.world.mocap.MocapClip.parents``): a rig's tree
# comes from its file, differs from rig to rig and is posed by joint rotations, while this one is fixed,
# is posed by bone vectors and has ``mid_hip`` and ``neck`` at midpoints rather than at rig joints;
# ``rigs`` maps the one onto the other.
BONES: tuple[tuple[str, str], ...] = (
    ("mid_hip", "r_hip"), ("r_hip", "r_knee"), ("r_knee", "r_ankle"), ("r_ankle", "r_big_toe"),
    ("mid_hip", "l_hip"), ("l_hip", "l_knee"), ("l_knee", "l_ankle"), ("l_ankle", "l_big_toe"),
    ("mid_hip", "neck"),
    ("neck", "r_shoulder"), ("r_shoulder", "r_elbow"), ("r_elbow", "r_wrist"),
    ("neck", "l_shoulder"), ("l_shoulder", "l_elbow"), ("l_elbow", "l_wrist"),
    ("neck", "head"), ("head", "nose"),
)
BONE_NAMES: tuple[str, ...] = tuple(child for _, child in BONES)
ROOT = "mid_hip"
_PARENT_IDX = np.array([_J[p] for p, _ in BONES], dtype=np.int64)
_CHILD_IDX = np.array([_J[c] for _, c in BONES], dtype=np.int64)
_B = {name: i for i, name in enumerate(BONE_NAMES)}
FOOT_JOINTS: tuple[str, ...] = ("l_ankle", "r_ankle", "l_big_toe", "r_big_toe")

# Height = ankle above the floor + leg + torso + neck + skull above its centre, with the two constants
# below (fractions of the foot and of the head->nose length).
_ANKLE_PER_FOOT = 0.5
_SKULL_TOP_PER_FACE = 1.1


def joint_index(name: str) -> int:
    """Index of ``name`` in ``WORLD_JOINTS``; KeyError lists the valid names."""
    try:
        return _J[name]
    except KeyError:
        raise KeyError(f"no world joint {name!r}; joints: {', '.join(WORLD_JOINTS)}") from None


@dataclass(frozen=True, eq=False)
class Motion3D:
    """A motion of the canonical skeleton.

    Attributes:
        positions: [T, 18, 3] float32 joint positions in metres, Y up, in ``WORLD_JOINTS`` order; the
            ground is y = 0 and the first frame's ``mid_hip`` is over the origin (x = z = 0).
        fps: frames per second.
        name: a short name (the file's stem).
        source: the file it came from ("" when made in memory).
    """

    positions: np.ndarray
    fps: float
    name: str = ""
    source: str = ""

    def __post_init__(self) -> None:
        pos = np.array(self.positions, dtype=np.float32, copy=True)
        if pos.ndim != 3 or pos.shape[1:] != (len(WORLD_JOINTS), 3):
            raise ValueError(f"Motion3D positions must be [T, {len(WORLD_JOINTS)}, 3], got {pos.shape}")
        if pos.shape[0] == 0:
            raise ValueError("Motion3D has no frames")
        if not np.isfinite(pos).all():
            raise ValueError("Motion3D positions must be finite")
        if not (np.isfinite(self.fps) and self.fps > 0):
            raise ValueError(f"Motion3D fps must be positive, got {self.fps}")
        pos.setflags(write=False)
        object.__setattr__(self, "positions", pos)
        object.__setattr__(self, "source", str(self.source))

    @property
    def num_frames(self) -> int:
        return int(self.positions.shape[0])

    def joint(self, name: str) -> np.ndarray:
        """[T, 3] trajectory of one joint."""
        return self.positions[:, joint_index(name)]


@dataclass(frozen=True)
class Skeleton:
    """A character: one length in metres per bone of ``BONES`` (named after the bone's child joint).

    Attributes:
        lengths: lengths in ``BONE_NAMES`` order.
        name: a label ("" for sampled characters).
    """

    lengths: tuple[float, ...]
    name: str = ""
    _array: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        arr = np.asarray(self.lengths, dtype=np.float64)
        if arr.shape != (len(BONES),):
            raise ValueError(f"Skeleton needs {len(BONES)} bone lengths, got {arr.shape}")
        if not (np.isfinite(arr).all() and (arr > 0).all()):
            raise ValueError("Skeleton bone lengths must be positive")
        object.__setattr__(self, "lengths", tuple(float(v) for v in arr))
        arr.setflags(write=False)
        object.__setattr__(self, "_array", arr)

    @classmethod
    def from_dict(cls, lengths: Mapping[str, float], name: str = "") -> Skeleton:
        missing = [b for b in BONE_NAMES if b not in lengths]
        if missing:
            raise ValueError(f"Skeleton.from_dict: missing bones {', '.join(missing)}")
        return cls(tuple(float(lengths[b]) for b in BONE_NAMES), name)

    @property
    def array(self) -> np.ndarray:
        """[17] read-only float64 lengths."""
        return self._array

    def length(self, bone: str) -> float:
        """Length of the bone ending in joint ``bone`` (e.g. ``"l_knee"`` is the left thigh)."""
        try:
            return self.lengths[_B[bone]]
        except KeyError:
            raise KeyError(f"no bone {bone!r}; bones: {', '.join(BONE_NAMES)}") from None

    def as_dict(self) -> dict[str, float]:
        return dict(zip(BONE_NAMES, self.lengths))

    @property
    def leg_length(self) -> float:
        """Mean of the two legs' thigh + shin."""
        return 0.5 * (self.length("l_knee") + self.length("l_ankle") + self.length("r_knee") + self.length("r_ankle"))

    @property
    def height(self) -> float:
        """Standing height in metres: ankle above the floor + leg + torso + neck + top of the skull."""
        foot = 0.5 * (self.length("l_big_toe") + self.length("r_big_toe"))
        return (
            _ANKLE_PER_FOOT * foot + self.leg_length + self.length("neck") + self.length("head")
            + _SKULL_TOP_PER_FACE * self.length("nose")
        )

    def scaled(self, factor: float, name: str | None = None) -> Skeleton:
        return Skeleton(tuple(v * factor for v in self.lengths), self.name if name is None else name)


# ---------------------------------------------------------------------------------------------------
# Measuring and retargeting.


def bone_vectors(positions: np.ndarray) -> np.ndarray:
    """[..., 17, 3] child - parent vector of every bone, from [..., 18, 3] joint positions."""
    return positions[..., _CHILD_IDX, :] - positions[..., _PARENT_IDX, :]


def bone_lengths(positions: np.ndarray) -> np.ndarray:
    """[..., 17] bone lengths of [..., 18, 3] joint positions."""
    return np.linalg.norm(bone_vectors(positions), axis=-1)


def skeleton_of(motion: Motion3D) -> Skeleton:
    """The motion's own character: the median length of each bone over the clip."""
    lengths = np.median(bone_lengths(motion.positions.astype(np.float64)), axis=0)
    return Skeleton(tuple(np.maximum(lengths, 1e-6)), name=motion.name)


def assemble(root: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """Joint positions from a root path and bone vectors.

    Args:
        root: [T, 3] ``mid_hip`` positions.
        vectors: [T, 17, 3] bone vectors in ``BONES`` order.

    Returns:
        [T, 18, 3] positions in ``WORLD_JOINTS`` order.
    """
    out = np.empty(root.shape[:-1] + (len(WORLD_JOINTS), 3), dtype=np.result_type(root, vectors))
    out[..., _J[ROOT], :] = root
    for b in range(len(BONES)):  # parents come before children in BONES
        out[..., _CHILD_IDX[b], :] = out[..., _PARENT_IDX[b], :] + vectors[..., b, :]
    return out


_REST_DIRECTIONS = {
    "r_hip": (-1, 0, 0), "r_knee": (0, -1, 0), "r_ankle": (0, -1, 0), "r_big_toe": (0, 0, 1),
    "l_hip": (1, 0, 0), "l_knee": (0, -1, 0), "l_ankle": (0, -1, 0), "l_big_toe": (0, 0, 1),
    "neck": (0, 1, 0), "r_shoulder": (-1, 0, 0), "l_shoulder": (1, 0, 0), "head": (0, 1, 0), "nose": (0, 0, 1),
}


def rest_pose(skeleton: Skeleton, arms: str = "down") -> np.ndarray:
    """[18, 3] float64 standing pose facing +Z (its left is +X), feet on y = 0, root over the origin.

    Args:
        skeleton: the character.
        arms: ``"down"`` (hanging) or ``"t"`` (T-pose, horizontal).
    """
    if arms not in ("down", "t"):
        raise ValueError(f"arms must be 'down' or 't', got {arms!r}")
    dirs = dict(_REST_DIRECTIONS)
    for side, sign in (("l", 1), ("r", -1)):
        d = (sign, 0, 0) if arms == "t" else (0, -1, 0)
        dirs[f"{side}_elbow"] = dirs[f"{side}_wrist"] = d
    vectors = np.array([dirs[b] for b in BONE_NAMES], dtype=np.float64) * skeleton.array[:, None]
    pos = assemble(np.zeros(3), vectors)
    return normalise_placement(pos[None])[0]


def _lowest_foot(positions: np.ndarray) -> np.ndarray:
    """[T] height of the lowest foot joint per frame."""
    return positions[:, [_J[n] for n in FOOT_JOINTS], 1].min(axis=1)


def retarget_3d(motion: Motion3D, skeleton: Skeleton, keep_feet_on_ground: bool = True) -> Motion3D:
    """Replay ``motion`` on ``skeleton``.

    Every bone keeps its direction in every frame and has its length scaled by (target length / the
    motion's median length), so the motion's own small length changes (spine bending) survive and
    replaying on ``skeleton_of(motion)`` is the identity. The root path (``mid_hip``, relative to the
    origin under the first frame's root) is scaled by the ratio of leg lengths. With
    ``keep_feet_on_ground``, every frame is then shifted vertically so that the lowest foot joint is at
    (leg ratio) x its original height: feet that were on the ground stay on it, jumps scale with the legs.

    Args:
        motion: the motion (``Motion3D`` conventions: ground y = 0, first root over the origin).
        skeleton: the character to replay it on.
        keep_feet_on_ground: apply the vertical foot correction.

    Returns:
        A new ``Motion3D`` with the same fps and name.
    """
    pos = motion.positions.astype(np.float64)
    source = skeleton_of(motion)
    ratios = skeleton.array / source.array  # [17]
    leg_ratio = skeleton.leg_length / source.leg_length
    vectors = bone_vectors(pos) * ratios[:, None]
    out = assemble(pos[:, _J[ROOT]] * leg_ratio, vectors)
    if keep_feet_on_ground:
        out[:, :, 1] += (leg_ratio * _lowest_foot(pos) - _lowest_foot(out))[:, None]
    return Motion3D(out.astype(np.float32), motion.fps, motion.name, motion.source)


def normalise_placement(positions: np.ndarray, ground_percentile: float = 2.0) -> np.ndarray:
    """Put a [T, 18, 3] Y-up clip on the ground (y = 0) with its first root over the origin.

    The ground is a low percentile of the per-frame lowest foot joint, so a stray frame does not sink
    the whole clip.
    """
    out = np.array(positions, dtype=np.float64, copy=True)
    out[:, :, 1] -= np.percentile(_lowest_foot(out), ground_percentile)
    root0 = out[0, _J[ROOT]]
    out[:, :, 0] -= root0[0]
    out[:, :, 2] -= root0[2]
    return out


def describe(skeleton: Skeleton) -> str:
    """One line: height and main segment lengths, for logs."""
    d = skeleton.as_dict()
    return (
        f"{skeleton.name or 'skeleton'}: height {skeleton.height:.2f} m, leg {skeleton.leg_length:.2f}, "
        f"torso {d['neck']:.2f}, arm {d['l_elbow'] + d['l_wrist']:.2f}, shoulders {d['l_shoulder'] + d['r_shoulder']:.2f}"
    )


__all__ = [
    "BONES",
    "BONE_NAMES",
    "FOOT_JOINTS",
    "ROOT",
    "WORLD_JOINTS",
    "Motion3D",
    "Skeleton",
    "assemble",
    "bone_lengths",
    "bone_vectors",
    "describe",
    "joint_index",
    "normalise_placement",
    "retarget_3d",
    "skeleton_of",
]
