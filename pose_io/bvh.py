"""Motion-capture readers: BVH (plain or gzip) and Acclaim ASF/AMC, with forward kinematics.

Both readers give a clip with the same small surface: ``names``, ``parents``, ``frame_time``,
``num_frames`` and ``global_transforms(joints) -> (rotations [T, N, 3, 3], positions [T, N, 3])`` in the
file's own units and axes. Mapping a rig onto a canonical joint set, units and the up axis are the
caller's business (see ``retarget.world.rigs``).

BVH conventions handled here:

* any rotation channel order: the local rotation is the product of the axis rotations in channel
  order (``Zrotation Xrotation Yrotation`` -> ``Rz @ Rx @ Ry``);
* position channels on any joint, not only the root (Bandai Namco has six on every joint). Exporters
  disagree on what they mean: some write the joint's full local translation (the channel values then
  replace the OFFSET; Bandai Namco, Blender), others a displacement from the OFFSET (the iClone rigs,
  whose root OFFSET holds the hip height and whose channels are a few centimetres). The reader decides
  per joint from the data: the channels are absolute when their mean, projected on the OFFSET's
  direction, is more than half the OFFSET's length (``BvhClip.absolute_positions``);
* End Sites are kept as joints named ``<parent>_End`` with no channels.
"""

from __future__ import annotations

import abc
import gzip
import math
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pose_io.errors import InputError

_AXES = {"X": 0, "Y": 1, "Z": 2}
_CHANNEL_RE = re.compile(r"^([XYZ])(position|rotation)$", re.IGNORECASE)


def read_text(path: str | Path) -> str:
    """Text of a plain or gzip-compressed file (gzip is recognised by its magic bytes, not the name)."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise InputError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise InputError(f"{path}: is a folder, not a file") from None
    if raw[:2] == b"\x1f\x8b":
        try:
            raw = gzip.decompress(raw)
        except (OSError, EOFError) as exc:
            raise InputError(f"{path}: broken gzip data ({exc})") from None
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        return raw.decode("latin-1")


def axis_rotations(axis: int, degrees: np.ndarray) -> np.ndarray:
    """Rotation matrices about one coordinate axis.

    Args:
        axis: 0, 1 or 2 for X, Y, Z.
        degrees: [...] angles in degrees (right-handed, counter-clockwise looking down the axis).

    Returns:
        [..., 3, 3] float64 rotation matrices.
    """
    rad = np.deg2rad(np.asarray(degrees, dtype=np.float64))
    c, s = np.cos(rad), np.sin(rad)
    out = np.zeros(rad.shape + (3, 3))
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    out[..., axis, axis] = 1.0
    out[..., i, i] = c
    out[..., j, j] = c
    out[..., i, j] = -s
    out[..., j, i] = s
    return out


def euler_matrices(angles: np.ndarray, order: str) -> np.ndarray:
    """Compose axis rotations in ``order``: ``order="ZXY"`` gives ``Rz(a0) @ Rx(a1) @ Ry(a2)``.

    Args:
        angles: [..., len(order)] degrees, one column per letter of ``order``.
        order: axis letters, e.g. ``"ZXY"``.

    Returns:
        [..., 3, 3] float64.
    """
    angles = np.asarray(angles, dtype=np.float64)
    out = np.broadcast_to(np.eye(3), angles.shape[:-1] + (3, 3)).copy()
    for k, letter in enumerate(order.upper()):
        out = out @ axis_rotations(_AXES[letter], angles[..., k])
    return out


def _ancestor_closure(parents: np.ndarray, joints: Iterable[int] | None) -> np.ndarray:
    """Sorted indices of ``joints`` and all their ancestors (all joints when ``joints`` is None)."""
    if joints is None:
        return np.arange(len(parents))
    keep: set[int] = set()
    for j in joints:
        j = int(j)
        while j >= 0 and j not in keep:
            keep.add(j)
            j = int(parents[j])
    return np.array(sorted(keep), dtype=np.int64)


def forward_kinematics(
    parents: np.ndarray,
    local_rotations: np.ndarray,
    local_translations: np.ndarray,
    joints: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Global rotations and positions of a joint tree, frame by frame.

    ``R_j = R_parent @ L_j`` and ``p_j = p_parent + R_parent @ t_j``; a root's parent is the identity at
    the origin. Parents must come before their children in ``joints``.

    Args:
        parents: [N] parent index per joint, -1 for a root.
        local_rotations: [T, K, 3, 3] local rotation of each joint in ``joints``.
        local_translations: [T, K, 3] translation of each joint from its parent, in the parent's frame.
        joints: [K] the joint indices the two arrays describe (sorted, closed under ``parents``).

    Returns:
        ``(rotations [T, N, 3, 3], positions [T, N, 3])``; joints not in ``joints`` are NaN.
    """
    t = local_rotations.shape[0]
    n = len(parents)
    rot = np.full((t, n, 3, 3), np.nan)
    pos = np.full((t, n, 3), np.nan)
    for k, j in enumerate(joints):
        p = int(parents[j])
        if p < 0:
            rot[:, j] = local_rotations[:, k]
            pos[:, j] = local_translations[:, k]
        else:
            rot[:, j] = rot[:, p] @ local_rotations[:, k]
            pos[:, j] = pos[:, p] + np.einsum("tab,tb->ta", rot[:, p], local_translations[:, k])
    return rot, pos


class _JointTree(abc.ABC):
    """What both clip types share: name lookup, frame rate and positions from ``global_transforms``."""

    names: tuple[str, ...]
    frame_time: float
    source: str

    @property
    def fps(self) -> float:
        return 1.0 / self.frame_time

    def index(self, name: str) -> int:
        """Index of joint ``name``; KeyError names the file."""
        try:
            return self.names.index(name)
        except ValueError:
            raise KeyError(f"{self.source or 'clip'}: no joint {name!r}") from None

    @abc.abstractmethod
    def global_transforms(self, joints: Iterable[int] | None = None) -> tuple[np.ndarray, np.ndarray]:
        """``(rotations [T, N, 3, 3], positions [T, N, 3])`` of the joints (all by default); each clip type's FK."""

    def global_positions(self, joints: Iterable[int] | None = None) -> np.ndarray:
        """[T, N, 3] world positions of every joint and End Site (file units and axes)."""
        return self.global_transforms(joints)[1]


@dataclass(frozen=True, eq=False)
class BvhClip(_JointTree):
    """A parsed BVH file.

    Attributes:
        names: joint names in file order; End Sites are named ``<parent>_End``.
        parents: [N] int parent index, -1 for a root.
        offsets: [N, 3] float64 OFFSET of each joint in its parent's frame (file units).
        channels: per joint, its channel names as written (``()`` for End Sites).
        channel_start: [N] int column of each joint's first channel in ``motion``.
        frame_time: seconds per frame.
        motion: [T, C] float64 channel values.
        absolute_positions: [N] bool, True where a joint's position channels replace its OFFSET
            (False: they are added to it; irrelevant for joints without position channels).
        source: the file it was read from.
    """

    names: tuple[str, ...]
    parents: np.ndarray
    offsets: np.ndarray
    channels: tuple[tuple[str, ...], ...]
    channel_start: np.ndarray
    frame_time: float
    motion: np.ndarray
    absolute_positions: np.ndarray
    source: str = ""

    @property
    def num_frames(self) -> int:
        return int(self.motion.shape[0])

    @property
    def end_sites(self) -> np.ndarray:
        """[N] bool, True for End Sites."""
        return np.array([name.endswith("_End") and not ch for name, ch in zip(self.names, self.channels)])

    def local_transforms(self, joints: Sequence[int] | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Local rotation and translation of each joint per frame.

        Args:
            joints: indices to compute (default all).

        Returns:
            ``(rotations [T, K, 3, 3], translations [T, K, 3])`` for the K joints asked for.
        """
        idx = np.arange(len(self.names)) if joints is None else np.asarray(joints, dtype=np.int64)
        t = self.num_frames
        rots = np.empty((t, len(idx), 3, 3))
        trans = np.empty((t, len(idx), 3))
        for k, j in enumerate(idx):
            chans = self.channels[j]
            start = int(self.channel_start[j])
            rot_cols, rot_order = [], ""
            pos = np.zeros((t, 3))
            has_pos = False
            for c, name in enumerate(chans):
                axis, kind = _CHANNEL_RE.match(name).groups()  # validated by the parser
                if kind.lower() == "rotation":
                    rot_cols.append(start + c)
                    rot_order += axis.upper()
                else:
                    pos[:, _AXES[axis.upper()]] = self.motion[:, start + c]
                    has_pos = True
            rots[:, k] = euler_matrices(self.motion[:, rot_cols], rot_order) if rot_order else np.eye(3)
            if has_pos and self.absolute_positions[j]:
                trans[:, k] = pos
            else:
                trans[:, k] = self.offsets[j] + pos
        return rots, trans

    def global_transforms(self, joints: Iterable[int] | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Forward kinematics.

        Args:
            joints: indices wanted (their ancestors are computed too); default all.

        Returns:
            ``(rotations [T, N, 3, 3], positions [T, N, 3])`` in file units and axes; joints that were
            not needed are NaN.
        """
        idx = _ancestor_closure(self.parents, joints)
        local_r, local_t = self.local_transforms(idx)
        return forward_kinematics(self.parents, local_r, local_t, idx)



class _Tokens:
    """Whitespace tokens of a BVH hierarchy with the line of each, for error messages."""

    def __init__(self, text: str, path: str) -> None:
        self.items: list[tuple[str, int]] = []
        for line_no, line in enumerate(text.splitlines(), 1):
            for tok in line.replace("{", " { ").replace("}", " } ").split():
                self.items.append((tok, line_no))
        self.pos = 0
        self.path = path

    def fail(self, what: str) -> InputError:
        line = self.items[min(self.pos, len(self.items) - 1)][1] if self.items else 0
        return InputError(f"{self.path}: broken BVH hierarchy near line {line}: {what}")

    def next(self) -> str:
        if self.pos >= len(self.items):
            raise self.fail("file ends inside the hierarchy")
        tok = self.items[self.pos][0]
        self.pos += 1
        return tok

    def name(self) -> str:
        """The rest of the current line, braces excluded: joint names may hold spaces ("Bip01 L Thigh")."""
        if self.pos >= len(self.items):
            raise self.fail("file ends inside the hierarchy")
        line = self.items[self.pos][1]
        parts = []
        while self.pos < len(self.items) and self.items[self.pos][1] == line and self.items[self.pos][0] not in "{}":
            parts.append(self.items[self.pos][0])
            self.pos += 1
        if not parts:
            raise self.fail("joint without a name")
        return " ".join(parts)

    def peek(self) -> str | None:
        return self.items[self.pos][0] if self.pos < len(self.items) else None

    def expect(self, want: str) -> None:
        tok = self.next()
        if tok.upper() != want.upper():
            raise self.fail(f"expected {want!r}, found {tok!r}")

    def number(self) -> float:
        tok = self.next()
        try:
            value = float(tok)
        except ValueError:
            raise self.fail(f"expected a number, found {tok!r}") from None
        if not math.isfinite(value):
            raise self.fail(f"non-finite number {tok!r}")
        return value


def _parse_hierarchy(text: str, path: str) -> tuple[list[str], list[int], list[list[float]], list[tuple[str, ...]]]:
    toks = _Tokens(text, path)
    toks.expect("HIERARCHY")
    names: list[str] = []
    parents: list[int] = []
    offsets: list[list[float]] = []
    channels: list[tuple[str, ...]] = []

    def joint(parent: int, name: str, end_site: bool) -> None:
        me = len(names)
        names.append(name)
        parents.append(parent)
        offsets.append([0.0, 0.0, 0.0])
        channels.append(())
        toks.expect("{")
        while True:
            tok = toks.next()
            key = tok.upper()
            if key == "}":
                return
            if key == "OFFSET":
                offsets[me] = [toks.number() for _ in range(3)]
            elif key == "CHANNELS" and not end_site:
                count = toks.number()
                if count != int(count) or not 0 <= count <= 64:
                    raise toks.fail(f"bad channel count {count}")
                chans = tuple(toks.next() for _ in range(int(count)))
                for c in chans:
                    if not _CHANNEL_RE.match(c):
                        raise toks.fail(f"unknown channel {c!r}")
                channels[me] = chans
            elif key == "JOINT" and not end_site:
                joint(me, toks.name(), False)
            elif key == "END" and not end_site:
                toks.expect("Site")
                joint(me, f"{name}_End", True)
            else:
                raise toks.fail(f"unexpected {tok!r} in joint {name!r}")

    while toks.peek() is not None and toks.peek().upper() == "ROOT":
        toks.next()
        joint(-1, toks.name(), False)
    if not names:
        raise toks.fail("no ROOT joint")
    if toks.peek() is not None:
        raise toks.fail(f"unexpected {toks.peek()!r} after the hierarchy")
    if len(set(names)) != len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        raise InputError(f"{path}: BVH joint names repeat: {', '.join(dup[:5])}")
    return names, parents, offsets, channels


def _header_value(line: str, key: str, path: str) -> str:
    head, _, value = line.partition(":")
    if head.strip().lower().replace(" ", "") != key:
        raise InputError(f"{path}: broken BVH motion header: expected '{key}:' but found {line.strip()[:40]!r}")
    return value.strip()


def parse_bvh(text: str, source: str = "<string>") -> BvhClip:
    """Parse BVH text (see ``read_bvh``)."""
    match = re.search(r"^\s*MOTION\s*$", text, flags=re.MULTILINE)
    if match is None:
        raise InputError(f"{source}: not a BVH file (no MOTION section)")
    names, parents, offsets, channels = _parse_hierarchy(text[: match.start()], source)
    counts = [len(c) for c in channels]
    total = int(sum(counts))
    if total == 0:
        raise InputError(f"{source}: BVH hierarchy has no channels")

    rest = text[match.end():].lstrip("\r\n").split("\n", 2)
    if len(rest) < 2:
        raise InputError(f"{source}: truncated BVH: the motion header is incomplete")
    frames_s = _header_value(rest[0], "frames", source)
    time_s = _header_value(rest[1], "frametime", source)
    try:
        n_frames = int(frames_s)
        frame_time = float(time_s)
    except ValueError:
        raise InputError(f"{source}: broken BVH motion header: frames {frames_s!r}, frame time {time_s!r}") from None
    if n_frames <= 0:
        raise InputError(f"{source}: BVH declares {n_frames} frames")
    if not (math.isfinite(frame_time) and frame_time > 0):
        raise InputError(f"{source}: BVH frame time must be positive, got {time_s!r}")

    body = rest[2] if len(rest) > 2 else ""
    lines = [ln for ln in body.splitlines() if ln.strip()]
    if len(lines) < n_frames:
        raise InputError(f"{source}: truncated BVH: declares {n_frames} frames but holds {len(lines)}")
    if len(lines) > n_frames:
        raise InputError(f"{source}: BVH declares {n_frames} frames but holds {len(lines)} lines of data")
    tokens = " ".join(lines).split()
    if len(tokens) != n_frames * total:
        for i, ln in enumerate(lines):
            got = len(ln.split())
            if got != total:
                raise InputError(
                    f"{source}: wrong channel count: frame {i + 1} has {got} values, the hierarchy declares {total}"
                )
    try:
        motion = np.array(tokens, dtype=np.float64).reshape(n_frames, total)
    except ValueError:
        bad = next(t for t in tokens if not _is_float(t))
        raise InputError(f"{source}: non-numeric value {bad[:20]!r} in the BVH motion data") from None
    if not np.isfinite(motion).all():
        raise InputError(f"{source}: non-finite values in the BVH motion data")

    parents_a = np.array(parents, dtype=np.int64)
    offsets_a = np.array(offsets, dtype=np.float64).reshape(-1, 3)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)
    absolute = np.zeros(len(names), dtype=bool)
    for j, chans in enumerate(channels):
        cols = [starts[j] + c for c, name in enumerate(chans) if name.lower().endswith("position")]
        if not cols:
            continue
        axes = [_AXES[name[0].upper()] for c, name in enumerate(chans) if name.lower().endswith("position")]
        mean = np.zeros(3)
        mean[axes] = motion[:, cols].mean(axis=0)
        norm = float(np.linalg.norm(offsets_a[j]))
        absolute[j] = norm > 0 and float(mean @ offsets_a[j]) / norm > 0.5 * norm
    return BvhClip(
        names=tuple(names),
        parents=parents_a,
        offsets=offsets_a,
        channels=tuple(channels),
        channel_start=starts,
        frame_time=frame_time,
        motion=motion,
        absolute_positions=absolute,
        source=source,
    )


def _is_float(tok: str) -> bool:
    try:
        float(tok)
    except ValueError:
        return False
    return True


def read_bvh(path: str | Path) -> BvhClip:
    """Read a BVH file, plain or gzip-compressed.

    Args:
        path: ``.bvh`` or ``.bvh.gz`` file.

    Returns:
        The parsed clip; ``clip.global_positions()`` gives ``[T, N, 3]`` by forward kinematics.

    Raises:
        InputError: missing, truncated or malformed file (one line naming the file and the problem).
    """
    return parse_bvh(read_text(path), str(path))


# ---------------------------------------------------------------------------------------------------
# Acclaim ASF (skeleton) + AMC (motion), as in the CMU database.


@dataclass(frozen=True, eq=False)
class AcclaimClip(_JointTree):
    """An ASF skeleton driven by an AMC motion, as a joint tree like ``BvhClip``.

    Each ASF bone becomes a joint at the bone's start (so ``lfemur`` is the hip joint and ``ltibia`` the
    knee); a leaf bone's end is the extra joint ``<bone>_End``. ``root`` is the root.

    Attributes:
        names: joint names.
        parents: [N] parent index, -1 for the root.
        vectors: [N, 3] each bone's rest vector (direction * length, ASF units, world axes); zero for
            End Sites and the root.
        axis_rotations: [N, 3, 3] each bone's ASF ``axis`` frame C.
        dof_rotations: [T, N, 3, 3] per-frame rotation M from the AMC degrees of freedom.
        root_positions: [T, 3] root translation per frame.
        frame_time: seconds per frame (AMC files do not store it; CMU's are 120 fps).
        source: ``"<asf> + <amc>"``.
    """

    names: tuple[str, ...]
    parents: np.ndarray
    vectors: np.ndarray
    axis_rotations: np.ndarray
    dof_rotations: np.ndarray
    root_positions: np.ndarray
    frame_time: float
    source: str = ""

    @property
    def num_frames(self) -> int:
        return int(self.root_positions.shape[0])

    def global_transforms(self, joints: Iterable[int] | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Forward kinematics: ``G_b = G_parent @ C_b @ M_b @ C_b^T``; a bone starts where its parent ends.

        Returns:
            ``(rotations [T, N, 3, 3], positions [T, N, 3])`` in ASF units and axes (NaN where not needed).
        """
        idx = _ancestor_closure(self.parents, joints)
        c = self.axis_rotations[idx]
        # [T, K, 3, 3]: the bone's own rotation expressed in its parent's frame.
        local_r = c[None] @ self.dof_rotations[:, idx] @ np.swapaxes(c, -1, -2)[None]
        t = self.num_frames
        local_t = np.zeros((t, len(idx), 3))
        for k, j in enumerate(idx):
            p = int(self.parents[j])
            if p < 0:
                local_t[:, k] = self.root_positions
            else:
                # The parent's bone vector is fixed in world axes at rest, so in the parent's frame it is
                # the rest vector itself.
                local_t[:, k] = self.vectors[p]
        return forward_kinematics(self.parents, local_r, local_t, idx)


def _asf_sections(text: str) -> dict[str, list[str]]:
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


def _dof_axis(name: str) -> int | None:
    name = name.lower()
    return {"rx": 0, "ry": 1, "rz": 2}.get(name)


def read_asf_amc(asf_path: str | Path, amc_path: str | Path, fps: float = 120.0) -> AcclaimClip:
    """Read an Acclaim skeleton and motion (CMU style).

    Args:
        asf_path: the ``.asf`` skeleton.
        amc_path: the ``.amc`` motion for it.
        fps: the motion's frame rate (AMC does not store it; CMU captured at 120 fps).

    Raises:
        InputError: missing or malformed files, or an AMC naming bones the ASF lacks.
    """
    asf_src, amc_src = str(asf_path), str(amc_path)
    sec = _asf_sections(read_text(asf_path))
    for need in ("root", "bonedata", "hierarchy"):
        if need not in sec:
            raise InputError(f"{asf_src}: not an ASF skeleton (no :{need} section)")
    deg = True
    for line in sec.get("units", []):
        parts = line.split()
        if len(parts) >= 2 and parts[0].lower() == "angle":
            deg = parts[1].lower().startswith("deg")

    def angles(vals: Sequence[float]) -> np.ndarray:
        a = np.asarray(vals, dtype=np.float64)
        return a if deg else np.rad2deg(a)

    try:
        root_info = {ln.split()[0].lower(): ln.split()[1:] for ln in sec["root"]}
        root_order = [s.upper() for s in root_info["order"]]
        root_axis = root_info.get("axis", ["XYZ"])[0].upper()
        root_orient = [float(v) for v in root_info.get("orientation", ["0", "0", "0"])]
        root_pos0 = np.array([float(v) for v in root_info.get("position", ["0", "0", "0"])])
    except (KeyError, IndexError, ValueError):
        raise InputError(f"{asf_src}: broken :root section") from None

    bones: dict[str, dict] = {}
    cur: dict | None = None
    for line in sec["bonedata"]:
        parts = line.split()
        key = parts[0].lower()
        try:
            if key == "begin":
                cur = {"dof": [], "direction": np.zeros(3), "length": 0.0, "axis": (np.zeros(3), "XYZ")}
            elif key == "end":
                if cur is None or "name" not in cur:
                    raise ValueError
                bones[cur["name"]] = cur
                cur = None
            elif cur is None:
                raise ValueError
            elif key == "name":
                cur["name"] = parts[1]
            elif key == "direction":
                cur["direction"] = np.array([float(v) for v in parts[1:4]])
            elif key == "length":
                cur["length"] = float(parts[1])
            elif key == "axis":
                cur["axis"] = (np.array([float(v) for v in parts[1:4]]), parts[4].upper() if len(parts) > 4 else "XYZ")
            elif key == "dof":
                cur["dof"] = [p.lower() for p in parts[1:]]
        except (ValueError, IndexError):
            raise InputError(f"{asf_src}: broken bone definition near {line[:40]!r}") from None

    parent_of: dict[str, str] = {}
    for line in sec["hierarchy"]:
        parts = line.split()
        if parts[0].lower() in ("begin", "end"):
            continue
        for child in parts[1:]:
            if child not in bones:
                raise InputError(f"{asf_src}: hierarchy names an unknown bone {child!r}")
            parent_of[child] = parts[0]

    # Parents before children: breadth-first from the root.
    names = ["root"]
    parents = [-1]
    frontier = ["root"]
    while frontier:
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
    n = len(names)
    vectors = np.zeros((n, 3))
    axes_c = np.broadcast_to(np.eye(3), (n, 3, 3)).copy()
    for j, name in enumerate(names):
        if name in bones:
            b = bones[name]
            vectors[j] = b["direction"] * b["length"]
            axes_c[j] = _acclaim_rotation(angles(b["axis"][0]), b["axis"][1])
    axes_c[0] = _acclaim_rotation(angles(root_orient), root_axis)

    # --- AMC
    frames: list[dict[str, list[float]]] = []
    for raw in read_text(amc_path).splitlines():
        line = raw.strip()
        if not line or line.startswith(("#", ":")):
            continue
        parts = line.split()
        if len(parts) == 1 and parts[0].isdigit():
            frames.append({})
            continue
        if not frames:
            raise InputError(f"{amc_src}: not an AMC motion (data before the first frame number)")
        try:
            frames[-1][parts[0]] = [float(v) for v in parts[1:]]
        except ValueError:
            raise InputError(f"{amc_src}: non-numeric value in line {line[:40]!r}") from None
    if not frames:
        raise InputError(f"{amc_src}: AMC motion has no frames")
    if not frames[-1]:
        frames.pop()  # a trailing frame number with no data (cut-off file)
    t = len(frames)
    dof_rot = np.broadcast_to(np.eye(3), (t, n, 3, 3)).copy()
    root_pos = np.zeros((t, 3))
    unknown = sorted({k for f in frames for k in f if k != "root" and k not in bones})
    if unknown:
        raise InputError(f"{amc_src}: bones not in {Path(asf_src).name}: {', '.join(unknown[:5])}")
    # Root: translations and rotations in the ASF's declared order.
    try:
        root_vals = np.array([f["root"] for f in frames], dtype=np.float64)
    except KeyError:
        raise InputError(f"{amc_src}: a frame has no root line") from None
    except ValueError:
        raise InputError(f"{amc_src}: root lines have different lengths") from None
    if root_vals.ndim != 2 or root_vals.shape[1] != len(root_order):
        raise InputError(f"{amc_src}: root lines must have {len(root_order)} values ({' '.join(root_order)})")
    rot_cols = [k for k, c in enumerate(root_order) if c.startswith("R")]
    for k, c in enumerate(root_order):
        if c.startswith("T"):
            root_pos[:, _AXES[c[1]]] = root_vals[:, k]
    root_pos += root_pos0
    rot = np.zeros((t, 3))
    for k in rot_cols:
        rot[:, _AXES[root_order[k][1]]] = angles(root_vals[:, k])
    dof_rot[:, 0] = _acclaim_rotation(rot, root_axis)
    for j, name in enumerate(names):
        if name not in bones or not bones[name]["dof"]:
            continue
        dofs = bones[name]["dof"]
        vals = np.zeros((t, 3))
        for i, f in enumerate(frames):
            v = f.get(name)
            if v is None:
                continue
            if len(v) != len(dofs):
                raise InputError(f"{amc_src}: frame {i + 1}: bone {name} has {len(v)} values, the ASF gives {len(dofs)} dof")
            for d, val in zip(dofs, v):
                ax = _dof_axis(d)
                if ax is not None:
                    vals[i, ax] = val
        dof_rot[:, j] = _acclaim_rotation(angles(vals), bones[name]["axis"][1])
    return AcclaimClip(
        names=tuple(names),
        parents=np.array(parents, dtype=np.int64),
        vectors=vectors,
        axis_rotations=axes_c,
        dof_rotations=dof_rot,
        root_positions=root_pos,
        frame_time=1.0 / fps,
        source=f"{asf_src} + {amc_src}",
    )



def _acclaim_rotation(xyz_degrees: np.ndarray, order: str) -> np.ndarray:
    """Acclaim rotation: about the axes in ``order``, each in the fixed frame, the first letter first.

    ``order="XYZ"`` gives ``Rz @ Ry @ Rx``.

    Args:
        xyz_degrees: [..., 3] angles about x, y, z (always in that column order).
        order: a permutation of ``"XYZ"``.

    Returns:
        [..., 3, 3] float64.
    """
    order = order.upper()
    if sorted(order) != ["X", "Y", "Z"]:
        raise InputError(f"ASF rotation order must be a permutation of XYZ, got {order!r}")
    cols = [_AXES[c] for c in reversed(order)]
    return euler_matrices(np.asarray(xyz_degrees)[..., cols], order[::-1])
