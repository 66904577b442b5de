"""From a motion-capture rig to the canonical skeleton: name tables, units, up axis, head points.

``load_motion`` reads a BVH (plain or gzip) or an Acclaim AMC (with its ASF), finds which naming the rig
uses, runs forward kinematics for the joints it needs and returns a ``Motion3D`` in metres, Y up, on the
ground, resampled to the requested frame rate. The readers and the forward kinematics live in
``retarget.world.mocap``.

Mapping keys (``RIG_KEYS``) are world joint names with two twists: ``neck`` is the rig's neck *base*
joint and ``head`` its head joint (the top of the neck); both are only used to place the skull. In the
world, ``neck`` is the midpoint of the shoulders and ``mid_hip`` that of the hips (OpenPose semantics),
and ``head`` (the centre of the skull) and ``nose`` are derived the same way for every rig: the rig's
head joint gives the head's orientation (calibrated once per clip against the body's up and facing
directions), and the skull centre and nose are placed at fixed fractions of the torso length along it.
A mapping may also name a ``nose`` joint, which is then used as is.

Units are found by measuring the rig's standing height in file units and picking the unit (metre, cm,
mm, inch or the CMU unit of 0.0254 / 0.45 m) that makes it closest to 1.7 m; the up axis is the world
axis closest to the average hips->shoulders direction.
"""

from __future__ import annotations

import json
import logging
import math
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType

import numpy as np

from pose_io.errors import InputError
from pose_io.resample import resample_values
from retarget.world.mocap import MocapClip, read_asf_amc, read_bvh
from retarget.world.skeleton import (
    WORLD_JOINTS,
    Motion3D,
    Skeleton,
    bone_lengths,
    joint_index,
    normalise_placement,
)

log = logging.getLogger(__name__)

# What a rig must give, and which world joints depend on each key (for error messages).
RIG_KEYS: tuple[str, ...] = (
    "l_hip", "r_hip", "l_knee", "r_knee", "l_ankle", "r_ankle", "l_big_toe", "r_big_toe",
    "l_shoulder", "r_shoulder", "l_elbow", "r_elbow", "l_wrist", "r_wrist", "neck", "head",
)
OPTIONAL_KEYS: tuple[str, ...] = ("nose",)
_NEEDED_BY: Mapping[str, tuple[str, ...]] = MappingProxyType({
    "l_hip": ("l_hip", "mid_hip"), "r_hip": ("r_hip", "mid_hip"),
    "l_shoulder": ("l_shoulder", "neck"), "r_shoulder": ("r_shoulder", "neck"),
    "neck": ("head", "nose"), "head": ("head", "nose"),
})

# Skull centre and nose relative to the rig's head joint, in torso lengths (mid_hip -> neck), along
# the head's own up (u) and forward (f) axes. For a 1.75 m adult (torso ~0.45 m) the skull centre is
# ~10 cm above and 2 cm in front of the head joint and the nose tip 10 cm in front of the skull centre.
_SKULL_UP, _SKULL_FWD = 0.22, 0.045
_NOSE_FWD, _NOSE_UP = 0.22, -0.04

# Candidate units, metres per file unit.
UNITS: Mapping[str, float] = MappingProxyType({
    "m": 1.0, "cm": 0.01, "mm": 0.001, "inch": 0.0254, "cmu": 0.0254 / 0.45,
})
_TYPICAL_HEIGHT = 1.7


def _norm(name: str) -> str:
    """Normalised joint name: no namespace (``mixamorig:``), no rig prefix, lower case, no separators."""
    name = name.rsplit(":", 1)[-1].lower()
    for prefix in ("cc_base_", "rl_", "mixamorig_", "mixamorig", "bip001", "bip01"):
        if name.startswith(prefix) and len(name) > len(prefix):
            name = name[len(prefix):]
            break
    return re.sub(r"[\s_.\-]", "", name)


@dataclass(frozen=True)
class RigNaming:
    """One naming convention: candidate rig names (normalised, see ``_norm``) for each key.

    Attributes:
        name: registry name.
        joints: key -> candidate names, first found wins.
        markers: normalised names that must all be present for this naming to be chosen.
        prefix: a prefix the raw names must carry (case-insensitive), e.g. ``"mixamorig"``.
    """

    name: str
    joints: Mapping[str, tuple[str, ...]]
    markers: tuple[str, ...] = ()
    prefix: str = ""


def _sided(left: Mapping[str, tuple[str, ...]], to_right: Callable[[str], str]) -> dict[str, tuple[str, ...]]:
    """A left-side table plus its right side, whose names ``to_right`` makes from the left ones."""
    out = dict(left)
    for key, names in left.items():
        if key.startswith("l_"):
            out["r_" + key[2:]] = tuple(to_right(n) for n in names)
    return out


def _word(n: str) -> str:
    return n.replace("left", "right", 1)


def _prefix(n: str) -> str:
    return "r" + n[1:]


def _suffix(n: str) -> str:
    return n[:-1] + "r"


_MOTIONBUILDER = _sided({
    "l_hip": ("leftupleg",), "l_knee": ("leftleg",), "l_ankle": ("leftfoot",),
    "l_big_toe": ("lefttoebase", "lefttoe", "lefttoes"), "l_shoulder": ("leftarm",),
    "l_elbow": ("leftforearm",), "l_wrist": ("lefthand",), "neck": ("neck", "neck1"), "head": ("head",),
}, _word)

RIGS: dict[str, RigNaming] = {
    # Mixamo: the MotionBuilder names in the "mixamorig:" namespace.
    "mixamo": RigNaming("mixamo", _MOTIONBUILDER, prefix="mixamorig"),
    # CMU converted by cgspeed, MotionBuilder-friendly: LHipJoint/LeftUpLeg..., LeftShoulder = clavicle.
    "cmu_motionbuilder": RigNaming("cmu_motionbuilder", _MOTIONBUILDER, markers=("lhipjoint", "lowerback")),
    # CMU converted by cgspeed, 3dsMax-friendly: LeftHip/LeftKnee/LeftAnkle, LeftCollar + LeftShoulder.
    "cmu_3dsmax": RigNaming("cmu_3dsmax", _sided({
        "l_hip": ("lefthip",), "l_knee": ("leftknee",), "l_ankle": ("leftankle",),
        "l_big_toe": ("lefttoe", "lefttoebase"), "l_shoulder": ("leftshoulder",), "l_elbow": ("leftelbow",),
        "l_wrist": ("leftwrist",), "neck": ("neck",), "head": ("head",),
    }, _word), markers=("leftcollar",)),
    "bandai_namco": RigNaming("bandai_namco", _sided({
        "l_hip": ("upperlegl",), "l_knee": ("lowerlegl",), "l_ankle": ("footl",), "l_big_toe": ("toesl",),
        "l_shoulder": ("upperarml",), "l_elbow": ("lowerarml",), "l_wrist": ("handl",), "neck": ("neck",),
        "head": ("head",),
    }, _suffix)),
    # Reallusion Character Creator / iClone: CC_Base_L_Thigh (older rigs: RL_ prefix).
    "character_creator": RigNaming("character_creator", _sided({
        "l_hip": ("lthigh",), "l_knee": ("lcalf",), "l_ankle": ("lfoot",), "l_big_toe": ("ltoebase",),
        "l_shoulder": ("lupperarm",), "l_elbow": ("lforearm",), "l_wrist": ("lhand",),
        "neck": ("necktwist01", "neck"), "head": ("head",),
    }, _prefix), markers=("lthigh", "lcalf")),
    # 3ds Max Biped: "Bip01 L Thigh", "Bip01 L Calf", ..., "Bip01 L Toe0".
    "max_biped": RigNaming("max_biped", _sided({
        "l_hip": ("lthigh",), "l_knee": ("lcalf",), "l_ankle": ("lfoot",), "l_big_toe": ("ltoe0",),
        "l_shoulder": ("lupperarm",), "l_elbow": ("lforearm",), "l_wrist": ("lhand",), "neck": ("neck",),
        "head": ("head",),
    }, _prefix), prefix="bip0"),
    # Acclaim ASF bones (CMU): a joint sits at its bone's start, so lfemur is the hip and ltibia the knee.
    "acclaim": RigNaming("acclaim", _sided({
        "l_hip": ("lfemur",), "l_knee": ("ltibia",), "l_ankle": ("lfoot",), "l_big_toe": ("ltoes",),
        "l_shoulder": ("lhumerus",), "l_elbow": ("lradius",), "l_wrist": ("lwrist",),
        "neck": ("lowerneck",), "head": ("head",),
    }, _prefix), markers=("lfemur",)),
    # Rokoko and most generic exports use the MotionBuilder names without the CMU extras.
    "rokoko": RigNaming("rokoko", _MOTIONBUILDER),
}


@dataclass(frozen=True)
class RigMapping:
    """A resolved mapping: rig joint index per key, and the naming it came from."""

    naming: str
    indices: Mapping[str, int]


def _missing_world(keys: list[str]) -> list[str]:
    out: list[str] = []
    for k in keys:
        for w in _NEEDED_BY.get(k, (k,)):
            if w not in out:
                out.append(w)
    return [w for w in WORLD_JOINTS if w in out]


def resolve_mapping(names: tuple[str, ...], source: str, mapping: Mapping[str, str] | None = None) -> RigMapping:
    """Find the rig joint for every key in ``RIG_KEYS`` (and the optional ``nose``).

    Args:
        names: the rig's joint names.
        source: file name for messages.
        mapping: user mapping key -> rig joint name; None tries every naming in ``RIGS``.

    Raises:
        InputError: the rig cannot be mapped; the message lists the world joints that are missing.
    """
    exact = {n: i for i, n in enumerate(names)}
    normal: dict[str, int] = {}
    for i, n in enumerate(names):
        normal.setdefault(_norm(n), i)
    if mapping is not None:
        unknown = sorted(set(mapping) - set(RIG_KEYS) - set(OPTIONAL_KEYS))
        if unknown:
            raise InputError(f"{source}: joint mapping has unknown keys {', '.join(unknown)}; valid: "
                             f"{', '.join(RIG_KEYS + OPTIONAL_KEYS)}")
        found: dict[str, int] = {}
        absent: list[str] = []
        for key in RIG_KEYS + OPTIONAL_KEYS:
            if key not in mapping:
                if key in RIG_KEYS:
                    absent.append(key)
                continue
            rig_name = str(mapping[key])
            idx = exact.get(rig_name, normal.get(_norm(rig_name)))
            if idx is None:
                absent.append(key)
            else:
                found[key] = idx
        if absent:
            raise InputError(f"{source}: the joint mapping leaves world joints unmapped: "
                             f"{', '.join(_missing_world(absent))}")
        return RigMapping("user", MappingProxyType(found))

    best: tuple[int, str, list[str]] | None = None
    for rig in RIGS.values():
        if rig.prefix and not any(n.lower().startswith(rig.prefix) for n in names):
            continue
        if any(m not in normal for m in rig.markers):
            continue
        found = {}
        absent = []
        for key, candidates in rig.joints.items():
            idx = next((normal[c] for c in candidates if c in normal), None)
            if idx is None:
                absent.append(key)
            else:
                found[key] = idx
        if not absent:
            return RigMapping(rig.name, MappingProxyType(found))
        if best is None or len(found) > best[0]:
            best = (len(found), rig.name, absent)
    missing = _missing_world(best[2]) if best else list(WORLD_JOINTS)
    hint = f" (closest naming: {best[1]})" if best and best[0] else ""
    raise InputError(f"{source}: unknown rig{hint}: cannot map world joints {', '.join(missing)}; "
                     "pass a JSON joint mapping")


def read_mapping(path: str | Path) -> dict[str, str]:
    """A user joint mapping from JSON: ``{"l_hip": "LThigh", ...}`` or ``{"joints": {...}}``."""
    path = Path(path)
    try:
        data = json.loads(path.read_text())
    except FileNotFoundError:
        raise InputError(f"{path}: no such mapping file") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: not valid JSON ({exc})") from None
    if isinstance(data, dict) and isinstance(data.get("joints"), dict):
        data = data["joints"]
    if not isinstance(data, dict) or not all(isinstance(k, str) and isinstance(v, str) for k, v in data.items()):
        raise InputError(f"{path}: a joint mapping must be a JSON object of world joint -> rig joint names")
    return data


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-12)


def _up_rotation(up: np.ndarray) -> np.ndarray:
    """[3, 3] proper rotation taking the coordinate axis nearest to ``up`` onto +Y."""
    axis = int(np.argmax(np.abs(up)))
    sign = float(np.sign(up[axis])) or 1.0
    src = np.zeros(3)
    src[axis] = sign
    dst = np.array([0.0, 1.0, 0.0])
    if np.allclose(src, dst):
        return np.eye(3)
    if np.allclose(src, -dst):
        return np.diag([1.0, -1.0, -1.0])  # 180 degrees about X
    k = np.cross(src, dst)  # unit, as src and dst are orthogonal unit axes
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + kx + kx @ kx  # Rodrigues for 90 degrees


def _head_points(
    head_pos: np.ndarray, head_rot: np.ndarray, neck_pos: np.ndarray, world: np.ndarray, torso: float
) -> tuple[np.ndarray, np.ndarray]:
    """Skull centre and nose, [T, 3] each, from the rig's head joint (see the module docstring)."""
    j = joint_index
    up_neck = _unit(head_pos - neck_pos)
    spine_up = _unit(world[:, j("neck")] - world[:, j("mid_hip")])
    left = world[:, j("l_hip")] - world[:, j("r_hip")] + world[:, j("l_shoulder")] - world[:, j("r_shoulder")]
    fwd = np.cross(left, spine_up)
    fwd = _unit(fwd - np.sum(fwd * up_neck, axis=-1, keepdims=True) * up_neck)
    # The same two directions in the head joint's own frame, averaged over the clip.
    rt = np.swapaxes(head_rot, -1, -2)
    u_local = _unit(np.einsum("tab,tb->a", rt, up_neck))
    f_local = np.einsum("tab,tb->a", rt, fwd)
    f_local = _unit(f_local - (f_local @ u_local) * u_local)
    u = np.einsum("tab,b->ta", head_rot, u_local)
    f = np.einsum("tab,b->ta", head_rot, f_local)
    skull = head_pos + torso * (_SKULL_UP * u + _SKULL_FWD * f)
    nose = skull + torso * (_NOSE_FWD * f + _NOSE_UP * u)
    return skull, nose


def guess_unit(lengths: np.ndarray) -> tuple[str, float]:
    """The unit (name, metres per unit) that makes a [17] bone-length set closest to 1.7 m tall."""
    height = Skeleton(tuple(np.maximum(lengths, 1e-9))).height
    best = min(UNITS.items(), key=lambda kv: abs(math.log(height * kv[1] / _TYPICAL_HEIGHT)))
    return best


def world_from_clip(clip: MocapClip, mapping: RigMapping, source: str) -> tuple[np.ndarray, str]:
    """World joints of a rig clip in metres, Y up, not yet placed on the ground.

    Returns:
        ``([T, 18, 3] float64, unit name)``.
    """
    idx = mapping.indices
    wanted = sorted(set(idx.values()))
    rot, pos = clip.global_transforms(wanted)
    t = pos.shape[0]
    world = np.zeros((t, len(WORLD_JOINTS), 3))
    direct = [k for k in idx if k not in ("neck", "head")]
    for key in direct:
        world[:, joint_index(key)] = pos[:, idx[key]]
    j = joint_index
    world[:, j("mid_hip")] = 0.5 * (world[:, j("l_hip")] + world[:, j("r_hip")])
    world[:, j("neck")] = 0.5 * (world[:, j("l_shoulder")] + world[:, j("r_shoulder")])
    torso = float(np.median(np.linalg.norm(world[:, j("neck")] - world[:, j("mid_hip")], axis=-1)))
    if not torso > 0:
        raise InputError(f"{source}: the rig's hips and shoulders coincide; cannot measure the body")
    skull, nose = _head_points(pos[:, idx["head"]], rot[:, idx["head"]], pos[:, idx["neck"]], world, torso)
    world[:, j("head")] = skull
    if "nose" not in idx:
        world[:, j("nose")] = nose
    if not np.isfinite(world).all():
        raise InputError(f"{source}: forward kinematics gave non-finite positions")

    up = np.mean(_unit(world[:, j("neck")] - world[:, j("mid_hip")]), axis=0)
    world = world @ _up_rotation(up).T
    lengths = np.median(bone_lengths(world), axis=0)
    unit_name, unit = guess_unit(lengths)
    log.debug("%s: naming %s, unit %s, %d frames", source, mapping.naming, unit_name, t)
    return world * unit, unit_name


def _find_asf(amc: Path) -> Path:
    """The ASF of an AMC: ``<subject>.asf`` next to it (CMU: 01_01.amc -> 01.asf), else the only one."""
    subject = amc.stem.split("_", 1)[0]
    for cand in (amc.with_name(subject + ".asf"), amc.with_name(subject + ".ASF")):
        if cand.is_file():
            return cand
    others = sorted(amc.parent.glob("*.asf")) + sorted(amc.parent.glob("*.ASF"))
    if len(others) == 1:
        return others[0]
    raise InputError(f"{amc}: cannot find its ASF skeleton ({subject}.asf next to it)")


def read_clip(path: str | Path, asf: str | Path | None = None) -> MocapClip:
    """Read a BVH (``.bvh``, ``.bvh.gz``) or AMC (``.amc``, skeleton from ``asf`` or found next to it)."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: no such file")
    if path.suffix.lower() == ".amc":
        return read_asf_amc(asf if asf is not None else _find_asf(path), path)
    return read_bvh(path)


def motion_name(path: str | Path) -> str:
    """File name without ``.gz`` and the format suffix."""
    name = Path(path).name
    for suffix in (".gz", ".bvh", ".amc"):
        if name.lower().endswith(suffix):
            name = name[: -len(suffix)]
    return name


def load_motion(
    path: str | Path,
    fps: float = 30.0,
    mapping: Mapping[str, str] | str | Path | None = None,
    asf: str | Path | None = None,
) -> Motion3D:
    """Read a mocap file and map it onto the canonical skeleton.

    Args:
        path: ``.bvh``, ``.bvh.gz`` or ``.amc``.
        fps: output frame rate (positions are resampled linearly).
        mapping: None to recognise the rig from ``RIGS``, a dict key -> rig joint name, or a JSON file.
        asf: the ASF skeleton of an AMC file (default: found next to it).

    Returns:
        ``Motion3D`` in metres, Y up, ground at y = 0, first root over the origin.

    Raises:
        InputError: unreadable file, unknown rig (listing the world joints it could not map).
    """
    if not (np.isfinite(fps) and fps > 0):
        raise InputError(f"fps must be positive, got {fps}")
    path = Path(path)
    clip = read_clip(path, asf)
    if isinstance(mapping, (str, Path)):
        mapping = read_mapping(mapping)
    resolved = resolve_mapping(clip.names, str(path), mapping)
    world, _ = world_from_clip(clip, resolved, str(path))
    src_fps = 1.0 / clip.frame_time
    if abs(src_fps - round(src_fps)) < 0.01:
        src_fps = float(round(src_fps))  # 0.0333333 s -> exactly 30 fps
    world = normalise_placement(resample_values(world, src_fps, fps))
    return Motion3D(world.astype(np.float32), float(fps), motion_name(path), str(path))


def rig_naming(path: str | Path, asf: str | Path | None = None) -> str:
    """Which naming in ``RIGS`` a file's rig uses (InputError when none fits)."""
    clip = read_clip(path, asf)
    return resolve_mapping(clip.names, str(path)).naming


__all__ = [
    "OPTIONAL_KEYS", "RIGS", "RIG_KEYS", "UNITS", "RigMapping", "RigNaming", "guess_unit", "load_motion",
    "motion_name", "read_clip", "read_mapping", "resolve_mapping", "rig_naming", "world_from_clip",
]
