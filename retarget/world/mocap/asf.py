"""Acclaim ASF skeletons, as in the CMU database: bones, their rest geometry and the joint tree.

Each ASF bone becomes a joint at the bone's start (so ``lfemur`` is the hip joint and ``ltibia`` the
knee); a leaf bone's end is the extra joint ``<bone>_End``; ``root`` is the root. The motion that drives
a skeleton is read by ``asf_amc``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pose_io.errors import InputError
from retarget.world.mocap.rotations import acclaim_rotation
from retarget.world.mocap.text import read_text


@dataclass
class AsfBone:
    """One ``begin ... end`` block of the ``:bonedata`` section.

    Attributes:
        name: the bone's name (None until its ``name`` line is read).
        direction: [3] unit rest direction, world axes.
        length: rest length (ASF units).
        axis: [3] angles of the bone's local frame C (ASF angle unit).
        axis_order: the axis order of ``axis`` and of the bone's AMC rotation, e.g. ``"XYZ"``.
        dof: the bone's AMC columns, lower case (``rx``, ``ry``, ``rz``, ...).
    """

    name: str | None = None
    direction: np.ndarray = field(default_factory=lambda: np.zeros(3))
    length: float = 0.0
    axis: np.ndarray = field(default_factory=lambda: np.zeros(3))
    axis_order: str = "XYZ"
    dof: list[str] = field(default_factory=list)


@dataclass(frozen=True)
class AsfRoot:
    """The ``:root`` section.

    Attributes:
        order: the AMC root columns, upper case, e.g. ``["TX", "TY", "TZ", "RX", "RY", "RZ"]``.
        axis: axis order of the root's rotations.
        orientation: [3] the root frame's angles (ASF angle unit).
        position: [3] rest position, added to the AMC translation.
    """

    order: list[str]
    axis: str
    orientation: list[float]
    position: np.ndarray


@dataclass(frozen=True, eq=False)
class AsfSkeleton:
    """A parsed ASF: joints in tree order (parents first) and their rest geometry.

    Attributes:
        names: joint names: ``root``, the bones breadth-first, then one ``<bone>_End`` per leaf bone.
        parents: parent index per joint, -1 for the root.
        bones: bone name -> definition.
        root: the root section.
        in_degrees: whether the file's angles are degrees (else radians).
        vectors: [N, 3] each bone's rest vector (direction * length); zero for the root and End Sites.
        axis_rotations: [N, 3, 3] each joint's frame C (identity for End Sites).
    """

    names: list[str]
    parents: list[int]
    bones: dict[str, AsfBone]
    root: AsfRoot
    in_degrees: bool
    vectors: np.ndarray
    axis_rotations: np.ndarray

    def degrees(self, values: Sequence[float] | np.ndarray) -> np.ndarray:
        """``values`` (any shape) as float64 degrees, from the file's angle unit."""
        return _degrees(values, self.in_degrees)


def _degrees(values: Sequence[float] | np.ndarray, in_degrees: bool) -> np.ndarray:
    a = np.asarray(values, dtype=np.float64)
    return a if in_degrees else np.rad2deg(a)


def _asf_sections(text: str) -> dict[str, list[str]]:
    """Lines of each ``:keyword`` section, comments and blank lines dropped."""
    sections: dict[str, list[str]] = {}
    current = None
    for raw in text.splitlines():
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        if line.startswith(":"):
            key, _, rest = line[1:].partition(" ")
            current = key.lower()
            sections.setdefault(current, [])
            if rest.strip():
                sections[current].append(rest.strip())
        elif current is not None:
            sections[current].append(line)
    return sections


def _angles_in_degrees(units: list[str]) -> bool:
    """Whether the ``:units`` section declares degrees (the default) rather than radians."""
    in_degrees = True
    for line in units:
        parts = line.split()
        if len(parts) >= 2 and parts[0].lower() == "angle":
            in_degrees = parts[1].lower().startswith("deg")
    return in_degrees


def _vector3(values: list[str]) -> np.ndarray:
    """Three finite numbers from the start of ``values``; ValueError otherwise (the callers name the line)."""
    v = np.array([float(x) for x in values[:3]])
    if v.shape != (3,) or not np.isfinite(v).all():
        raise ValueError("expected three finite numbers")
    return v


def _parse_root(lines: list[str], src: str) -> AsfRoot:
    try:
        info = {ln.split()[0].lower(): ln.split()[1:] for ln in lines}
        order = [s.upper() for s in info["order"]]
        if not all(len(c) == 2 and c[0] in "TR" and c[1] in "XYZ" for c in order):
            raise ValueError("root order must name TX..RZ channels")
        return AsfRoot(
            order=order,
            axis=info.get("axis", ["XYZ"])[0].upper(),
            orientation=list(_vector3(info.get("orientation", ["0", "0", "0"]))),
            position=_vector3(info.get("position", ["0", "0", "0"])),
        )
    except (KeyError, IndexError, ValueError):
        raise InputError(f"{src}: broken :root section") from None


def _parse_bones(lines: list[str], src: str) -> dict[str, AsfBone]:
    """The ``:bonedata`` section: bone name -> its definition."""
    bones: dict[str, AsfBone] = {}
    cur: AsfBone | None = None
    for line in lines:
        parts = line.split()
        key = parts[0].lower()
        try:
            if key == "begin":
                cur = AsfBone()
            elif key == "end":
                if cur is None or cur.name is None:
                    raise ValueError
                bones[cur.name] = cur
                cur = None
            elif cur is None:
                raise ValueError
            elif key == "name":
                cur.name = parts[1]
            elif key == "direction":
                cur.direction = _vector3(parts[1:4])
            elif key == "length":
                cur.length = float(parts[1])
                if not math.isfinite(cur.length):
                    raise ValueError
            elif key == "axis":
                cur.axis = _vector3(parts[1:4])
                cur.axis_order = parts[4].upper() if len(parts) > 4 else "XYZ"
            elif key == "dof":
                cur.dof = [p.lower() for p in parts[1:]]
        except (ValueError, IndexError):
            raise InputError(f"{src}: broken bone definition near {line[:40]!r}") from None
    return bones


def _parse_parents(lines: list[str], bones: dict[str, AsfBone], src: str) -> dict[str, str]:
    """The ``:hierarchy`` section: child bone -> parent bone (or ``root``)."""
    parent_of: dict[str, str] = {}
    for line in lines:
        parts = line.split()
        if parts[0].lower() in ("begin", "end"):
            continue
        for child in parts[1:]:
            if child not in bones:
                raise InputError(f"{src}: hierarchy names an unknown bone {child!r}")
            parent_of[child] = parts[0]
    return parent_of


def _order_joints(parent_of: dict[str, str]) -> tuple[list[str], list[int]]:
    """Joint names and parent indices, parents before children, plus an ``_End`` joint per leaf."""
    names = ["root"]
    parents = [-1]
    frontier = ["root"]
    while frontier:  # breadth-first from the root
        nxt = []
        for p in frontier:
            for child in [c for c, par in parent_of.items() if par == p]:
                names.append(child)
                parents.append(names.index(p))
                nxt.append(child)
        frontier = nxt
    has_child = set(parents)
    for j in range(1, len(names)):
        if j not in has_child:
            names.append(f"{names[j]}_End")
            parents.append(j)
    return names, parents


def read_asf(path: str | Path) -> AsfSkeleton:
    """Read an Acclaim ``.asf`` skeleton.

    Args:
        path: the file (plain or gzip).

    Raises:
        InputError: a missing file, a missing section, or a malformed root, bone or hierarchy.
    """
    src = str(path)
    sec = _asf_sections(read_text(path))
    for need in ("root", "bonedata", "hierarchy"):
        if need not in sec:
            raise InputError(f"{src}: not an ASF skeleton (no :{need} section)")
    in_degrees = _angles_in_degrees(sec.get("units", []))
    root = _parse_root(sec["root"], src)
    bones = _parse_bones(sec["bonedata"], src)
    names, parents = _order_joints(_parse_parents(sec["hierarchy"], bones, src))
    n = len(names)
    vectors = np.zeros((n, 3))
    axes_c = np.broadcast_to(np.eye(3), (n, 3, 3)).copy()
    for j, name in enumerate(names):
        if name in bones:
            b = bones[name]
            with np.errstate(over="ignore", invalid="ignore"):
                vectors[j] = b.direction * b.length
            if not np.isfinite(vectors[j]).all():
                raise InputError(f"{src}: bone {name}: direction x length is out of range")
            axes_c[j] = acclaim_rotation(_degrees(b.axis, in_degrees), b.axis_order)
    axes_c[0] = acclaim_rotation(_degrees(root.orientation, in_degrees), root.axis)
    return AsfSkeleton(names, parents, bones, root, in_degrees, vectors, axes_c)


__all__ = ["AsfBone", "AsfRoot", "AsfSkeleton", "read_asf"]
