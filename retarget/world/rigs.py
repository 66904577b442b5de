"""From a motion-capture rig to the canonical skeleton: name tables, units, up axis, head points.

``load_motion`` reads a BVH (plain or gzip) or an Acclaim AMC (with its ASF), finds which naming the rig
uses (``retarget.world.rig_names``), runs forward kinematics for the joints it needs and returns a ``Motion3D`` in metres, Y up, on the
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

import logging
import math
from collections.abc import Mapping
from pathlib import Path
from types import MappingProxyType

import numpy as np

from pose_io.errors import InputError
from pose_io.resample import resample_values
from retarget.world.mocap import MocapClip, read_asf_amc, read_bvh
from retarget.world.rig_names import RigMapping, read_mapping, resolve_mapping
from retarget.world.skeleton import (
    WORLD_JOINTS,
    Motion3D,
    Skeleton,
    bone_lengths,
    joint_index,
    normalise_placement,
)

log = logging.getLogger(__name__)

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


__all__ = ["UNITS", "guess_unit", "load_motion", "motion_name", "read_clip", "rig_naming", "world_from_clip"]
