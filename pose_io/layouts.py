"""Joint layouts as data: names, limbs, left/right mirror pairs and drawing colours.

Every index into a pose array comes from a name (``layout.index("mid_hip")``). Conversions between
layouts are a table of rules: a target joint is copied from a source joint of the same name, or made
as the mean of a few source joints (e.g. OpenPose's Neck from the two shoulders of MediaPipe).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np

from pose_io.errors import InputError

RGB = tuple[int, int, int]


@dataclass(frozen=True)
class JointLayout:
    """A named joint set.

    Attributes:
        name: registry name, e.g. ``"body25"``.
        joints: joint names in array order.
        limbs: pairs of joint names drawn as bones (parent first).
        colors: one RGB colour per joint, used for the joint and the limb that ends in it.
    """

    name: str
    joints: tuple[str, ...]
    limbs: tuple[tuple[str, str], ...]
    colors: tuple[RGB, ...]
    _index: Mapping[str, int] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if len(set(self.joints)) != len(self.joints):
            raise ValueError(f"layout {self.name}: duplicate joint names")
        if len(self.colors) != len(self.joints):
            raise ValueError(f"layout {self.name}: {len(self.colors)} colours for {len(self.joints)} joints")
        index = MappingProxyType({n: i for i, n in enumerate(self.joints)})
        for a, b in self.limbs:
            if a not in index or b not in index:
                raise ValueError(f"layout {self.name}: limb ({a}, {b}) names an unknown joint")
        object.__setattr__(self, "_index", index)

    def __len__(self) -> int:
        return len(self.joints)

    def index(self, name: str) -> int:
        """Array index of joint ``name``; KeyError lists the valid names."""
        try:
            return self._index[name]
        except KeyError:
            raise KeyError(f"layout {self.name} has no joint {name!r}; joints: {', '.join(self.joints)}") from None

    def indices(self, names: tuple[str, ...] | list[str]) -> list[int]:
        return [self.index(n) for n in names]

    def has(self, name: str) -> bool:
        return name in self._index

    @property
    def limb_indices(self) -> np.ndarray:
        """[L, 2] int array of (parent, child) joint indices."""
        return np.array([(self._index[a], self._index[b]) for a, b in self.limbs], dtype=np.int64).reshape(-1, 2)

    @property
    def mirror(self) -> np.ndarray:
        """[J] permutation that swaps left and right joints (``l_x`` <-> ``r_x``)."""
        perm = np.arange(len(self.joints))
        for i, n in enumerate(self.joints):
            other = _swap_side(n)
            if other != n and other in self._index:
                perm[i] = self._index[other]
        return perm


def _swap_side(name: str) -> str:
    if name.startswith("l_"):
        return "r_" + name[2:]
    if name.startswith("r_"):
        return "l_" + name[2:]
    if name.endswith("_left"):
        return name[: -len("left")] + "right"
    if name.endswith("_right"):
        return name[: -len("right")] + "left"
    return name


# OpenPose's render colours (per joint, RGB), from its BODY_25 rendering table.
_BODY25_COLORS: tuple[RGB, ...] = (
    (255, 0, 85), (255, 0, 0), (255, 85, 0), (255, 170, 0), (255, 255, 0), (170, 255, 0), (85, 255, 0),
    (0, 255, 0), (255, 0, 0), (0, 255, 85), (0, 255, 170), (0, 255, 255), (0, 170, 255), (0, 85, 255),
    (0, 0, 255), (255, 0, 170), (170, 0, 255), (255, 0, 255), (85, 0, 255), (0, 0, 255), (0, 0, 255),
    (0, 0, 255), (0, 255, 255), (0, 255, 255), (0, 255, 255),
)

_BODY25_JOINTS = (
    "nose", "neck", "r_shoulder", "r_elbow", "r_wrist", "l_shoulder", "l_elbow", "l_wrist", "mid_hip",
    "r_hip", "r_knee", "r_ankle", "l_hip", "l_knee", "l_ankle", "r_eye", "l_eye", "r_ear", "l_ear",
    "l_big_toe", "l_small_toe", "l_heel", "r_big_toe", "r_small_toe", "r_heel",
)

_BODY15_LIMBS = (
    ("neck", "mid_hip"), ("neck", "r_shoulder"), ("neck", "l_shoulder"), ("r_shoulder", "r_elbow"),
    ("r_elbow", "r_wrist"), ("l_shoulder", "l_elbow"), ("l_elbow", "l_wrist"), ("mid_hip", "r_hip"),
    ("r_hip", "r_knee"), ("r_knee", "r_ankle"), ("mid_hip", "l_hip"), ("l_hip", "l_knee"),
    ("l_knee", "l_ankle"), ("neck", "nose"),
)

BODY25 = JointLayout(
    name="body25",
    joints=_BODY25_JOINTS,
    limbs=_BODY15_LIMBS + (
        ("nose", "r_eye"), ("r_eye", "r_ear"), ("nose", "l_eye"), ("l_eye", "l_ear"),
        ("l_ankle", "l_big_toe"), ("l_big_toe", "l_small_toe"), ("l_ankle", "l_heel"),
        ("r_ankle", "r_big_toe"), ("r_big_toe", "r_small_toe"), ("r_ankle", "r_heel"),
    ),
    colors=_BODY25_COLORS,
)

# The first 15 BODY_25 joints: the network's layout and that of the authors' released weights.
BODY15 = JointLayout(name="body15", joints=_BODY25_JOINTS[:15], limbs=_BODY15_LIMBS, colors=_BODY25_COLORS[:15])

_COCO18_JOINTS = (
    "nose", "neck", "r_shoulder", "r_elbow", "r_wrist", "l_shoulder", "l_elbow", "l_wrist", "r_hip",
    "r_knee", "r_ankle", "l_hip", "l_knee", "l_ankle", "r_eye", "l_eye", "r_ear", "l_ear",
)
COCO18 = JointLayout(
    name="coco18",
    joints=_COCO18_JOINTS,
    limbs=(
        ("neck", "r_shoulder"), ("neck", "l_shoulder"), ("r_shoulder", "r_elbow"), ("r_elbow", "r_wrist"),
        ("l_shoulder", "l_elbow"), ("l_elbow", "l_wrist"), ("neck", "r_hip"), ("r_hip", "r_knee"),
        ("r_knee", "r_ankle"), ("neck", "l_hip"), ("l_hip", "l_knee"), ("l_knee", "l_ankle"),
        ("neck", "nose"), ("nose", "r_eye"), ("r_eye", "r_ear"), ("nose", "l_eye"), ("l_eye", "l_ear"),
    ),
    colors=tuple(_BODY25_COLORS[BODY25.index(n)] for n in _COCO18_JOINTS),
)

# MS-COCO's 17 keypoints (COCO results files, AlphaPose): no neck.
_COCO17_JOINTS = (
    "nose", "l_eye", "r_eye", "l_ear", "r_ear", "l_shoulder", "r_shoulder", "l_elbow", "r_elbow",
    "l_wrist", "r_wrist", "l_hip", "r_hip", "l_knee", "r_knee", "l_ankle", "r_ankle",
)
COCO17 = JointLayout(
    name="coco17",
    joints=_COCO17_JOINTS,
    limbs=(
        ("l_shoulder", "r_shoulder"), ("l_shoulder", "l_elbow"), ("l_elbow", "l_wrist"),
        ("r_shoulder", "r_elbow"), ("r_elbow", "r_wrist"), ("l_shoulder", "l_hip"), ("r_shoulder", "r_hip"),
        ("l_hip", "r_hip"), ("l_hip", "l_knee"), ("l_knee", "l_ankle"), ("r_hip", "r_knee"),
        ("r_knee", "r_ankle"), ("nose", "l_eye"), ("nose", "r_eye"), ("l_eye", "l_ear"), ("r_eye", "r_ear"),
    ),
    colors=tuple(_BODY25_COLORS[BODY25.index(n)] for n in _COCO17_JOINTS),
)

_MP33_JOINTS = (
    "nose", "l_eye_inner", "l_eye", "l_eye_outer", "r_eye_inner", "r_eye", "r_eye_outer", "l_ear", "r_ear",
    "mouth_left", "mouth_right", "l_shoulder", "r_shoulder", "l_elbow", "r_elbow", "l_wrist", "r_wrist",
    "l_pinky", "r_pinky", "l_index", "r_index", "l_thumb", "r_thumb", "l_hip", "r_hip", "l_knee", "r_knee",
    "l_ankle", "r_ankle", "l_heel", "r_heel", "l_foot_index", "r_foot_index",
)


def _mp_color(name: str) -> RGB:
    if BODY25.has(name):
        return _BODY25_COLORS[BODY25.index(name)]
    if name.startswith("l_"):
        return (0, 85, 255)
    if name.startswith("r_"):
        return (255, 85, 0)
    return (255, 0, 170)


MEDIAPIPE33 = JointLayout(
    name="mediapipe33",
    joints=_MP33_JOINTS,
    limbs=(
        ("l_shoulder", "r_shoulder"), ("l_shoulder", "l_elbow"), ("l_elbow", "l_wrist"), ("l_wrist", "l_pinky"),
        ("l_wrist", "l_index"), ("l_wrist", "l_thumb"), ("r_shoulder", "r_elbow"), ("r_elbow", "r_wrist"),
        ("r_wrist", "r_pinky"), ("r_wrist", "r_index"), ("r_wrist", "r_thumb"), ("l_shoulder", "l_hip"),
        ("r_shoulder", "r_hip"), ("l_hip", "r_hip"), ("l_hip", "l_knee"), ("l_knee", "l_ankle"),
        ("l_ankle", "l_heel"), ("l_heel", "l_foot_index"), ("r_hip", "r_knee"), ("r_knee", "r_ankle"),
        ("r_ankle", "r_heel"), ("r_heel", "r_foot_index"), ("nose", "l_eye"), ("nose", "r_eye"),
        ("l_eye", "l_ear"), ("r_eye", "r_ear"), ("mouth_left", "mouth_right"),
    ),
    colors=tuple(_mp_color(n) for n in _MP33_JOINTS),
)

# The pose maps of reference models: body15 and the details that tell front from back and show the hands and
# feet (face: eyes, ears, mouth corners; hands: thumb, index and pinky; feet: heel and big toe). MediaPipe's 33
# landmarks give all of them, BODY_25 all but the mouth and hands. Colours: the body's, then per part and side.
_DETAIL_JOINTS = (
    "r_eye", "l_eye", "r_ear", "l_ear", "mouth_right", "mouth_left",
    "r_thumb", "r_index", "r_pinky", "l_thumb", "l_index", "l_pinky",
    "r_heel", "r_big_toe", "l_heel", "l_big_toe",
)
_DETAIL_COLORS: tuple[RGB, ...] = (
    (255, 255, 255), (255, 255, 255), (255, 0, 255), (0, 255, 255), (255, 128, 128), (255, 128, 128),
    (255, 200, 0), (255, 140, 0), (255, 80, 0), (0, 200, 255), (0, 140, 255), (0, 80, 255),
    (200, 255, 0), (120, 255, 0), (0, 255, 200), (0, 255, 120),
)
BODY31 = JointLayout(
    name="body31",
    joints=_BODY25_JOINTS[:15] + _DETAIL_JOINTS,
    limbs=_BODY15_LIMBS + (
        ("nose", "r_eye"), ("nose", "l_eye"), ("r_eye", "r_ear"), ("l_eye", "l_ear"), ("mouth_right", "mouth_left"),
        ("r_wrist", "r_thumb"), ("r_wrist", "r_index"), ("r_wrist", "r_pinky"),
        ("l_wrist", "l_thumb"), ("l_wrist", "l_index"), ("l_wrist", "l_pinky"),
        ("r_ankle", "r_heel"), ("r_ankle", "r_big_toe"), ("r_heel", "r_big_toe"),
        ("l_ankle", "l_heel"), ("l_ankle", "l_big_toe"), ("l_heel", "l_big_toe"),
    ),
    colors=_BODY25_COLORS[:15] + _DETAIL_COLORS,
)

LAYOUTS: dict[str, JointLayout] = {
    lay.name: lay for lay in (BODY25, BODY15, COCO18, COCO17, MEDIAPIPE33, BODY31)
}


def get_layout(name: str) -> JointLayout:
    """Layout by registry name; an unknown name raises ValueError listing the valid ones."""
    try:
        return LAYOUTS[name]
    except KeyError:
        raise ValueError(f"unknown joint layout {name!r}; valid: {', '.join(sorted(LAYOUTS))}") from None


# How a joint missing from a source layout is made from joints it has: the mean of the listed joints.
# A derived joint is missing whenever any joint it needs is missing.
DERIVED: Mapping[str, tuple[str, ...]] = MappingProxyType({
    "neck": ("l_shoulder", "r_shoulder"),
    "mid_hip": ("l_hip", "r_hip"),
    "l_big_toe": ("l_foot_index",),
    "r_big_toe": ("r_foot_index",),
})


def conversion_plan(source: JointLayout, target: JointLayout) -> list[tuple[int, ...]]:
    """For each target joint, the source indices whose mean gives it (empty: cannot be made).

    Args:
        source: layout of the data.
        target: layout wanted.

    Returns:
        A list of ``len(target)`` tuples of source indices.
    """
    return list(_plan(source, target).sources)


@dataclass(frozen=True)
class _Plan:
    """A conversion worked out once per pair of layouts (:func:`_plan`): what :func:`conversion_plan` returns,
    and the same as slices for :func:`convert_arrays`."""

    sources: tuple[tuple[int, ...], ...]  # per target joint, as conversion_plan
    copies: tuple[tuple[slice, slice], ...]  # (target joints, source joints): runs copied from one joint each
    derived: tuple[tuple[int, list[int]], ...]  # (target joint, its source joints) made as a mean of several
    complete: bool  # every target joint can be made (nothing stays NaN by default)


_PLANS: dict[tuple[str, tuple[str, ...], str, tuple[str, ...]], _Plan] = {}


def _plan(source: JointLayout, target: JointLayout) -> _Plan:
    """The conversion of ``source`` into ``target``, cached by their names and joints (layouts are data)."""
    key = (source.name, source.joints, target.name, target.joints)
    plan = _PLANS.get(key)
    if plan is None:
        sources: list[tuple[int, ...]] = []
        for name in target.joints:
            if source.has(name):
                sources.append((source.index(name),))
            elif name in DERIVED and all(source.has(n) for n in DERIVED[name]):
                sources.append(tuple(source.index(n) for n in DERIVED[name]))
            else:
                sources.append(())
        runs: list[list[int]] = []  # [target start, source start, length] of consecutive copies
        for j, src in enumerate(sources):
            if len(src) != 1:
                continue
            if runs and runs[-1][0] + runs[-1][2] == j and runs[-1][1] + runs[-1][2] == src[0]:
                runs[-1][2] += 1
            else:
                runs.append([j, src[0], 1])
        plan = _Plan(
            tuple(sources),
            tuple((slice(j, j + n), slice(i, i + n)) for j, i, n in runs),
            tuple((j, list(src)) for j, src in enumerate(sources) if len(src) > 1),
            all(sources),
        )
        _PLANS[key] = plan
    return plan


def convert_arrays(
    joints: np.ndarray, confidence: np.ndarray, source: JointLayout, target: JointLayout
) -> tuple[np.ndarray, np.ndarray]:
    """Map ``[T, Js, 2]`` joints and ``[T, Js]`` confidence from ``source`` to ``target``.

    Joints the source cannot give come out as NaN with confidence 0.

    Returns:
        ``([T, Jt, 2] float32, [T, Jt] float32)``.
    """
    if source.name == target.name:
        return joints.astype(np.float32, copy=True), confidence.astype(np.float32, copy=True)
    plan = _plan(source, target)
    out = convert_joints(joints, source, target)
    conf = np.empty((joints.shape[0], len(target)), dtype=np.float32)
    if not plan.complete:
        conf.fill(0.0)
    for to, of in plan.copies:
        conf[:, to] = confidence[:, of]
    for j, idx in plan.derived:
        conf[:, j] = confidence[:, idx].min(axis=1)
    missing = np.isnan(out[..., 0])  # [T, Jt]: convert_joints made both coordinates NaN
    if missing.any():
        conf[missing] = 0.0
    return out, conf


def convert_joints(joints: np.ndarray, source: JointLayout, target: JointLayout) -> np.ndarray:
    """The joints of :func:`convert_arrays` alone: ``[T, Js, 2]`` in ``source`` -> ``[T, Jt, 2]`` float32."""
    if source.name == target.name:
        return joints.astype(np.float32, copy=True)
    plan = _plan(source, target)
    out = np.empty((joints.shape[0], len(target), 2), dtype=np.float32)
    if not plan.complete:
        out.fill(np.nan)
    for to, of in plan.copies:
        # "+ 0" is what the mean of one value gave (it turns -0.0 into 0.0): the same numbers, one pass.
        np.add(joints[:, of], np.float32(0.0), out=out[:, to], casting="same_kind")
    for j, idx in plan.derived:
        out[:, j] = joints[:, idx].mean(axis=1)  # NaN propagates: a derived joint with a missing part is missing
    nan = np.isnan(out)
    missing = nan[..., 0] | nan[..., 1]  # [T, Jt]
    if missing.any():
        out[missing] = np.nan
    return out


def require_convertible(source: JointLayout, target: JointLayout, needed: tuple[str, ...] | None = None) -> None:
    """Raise InputError when ``source`` cannot give the ``needed`` joints of ``target`` (all by default)."""
    plan = dict(zip(target.joints, conversion_plan(source, target)))
    names = needed if needed is not None else target.joints
    lacking = [n for n in names if not plan[n]]
    if lacking:
        raise InputError(f"layout {source.name} cannot give {target.name} joints: {', '.join(lacking)}")
