"""Which rig joint is which: the naming conventions of common motion-capture rigs and user joint mappings.

``resolve_mapping`` finds, for every key in ``RIG_KEYS`` (world joint names; ``neck`` and ``head`` are the
rig's neck base and head joints), the joint of a rig, trying every naming in ``RIGS`` or following a user
mapping (``read_mapping`` reads one from JSON). Names are compared normalised: no namespace or rig prefix,
lower case, no separators. ``retarget.world.rigs`` turns the mapped joints into world positions.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType

from pose_io.errors import InputError
from retarget.world.skeleton import WORLD_JOINTS

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


__all__ = ["OPTIONAL_KEYS", "RIGS", "RIG_KEYS", "RigMapping", "RigNaming", "read_mapping", "resolve_mapping"]
