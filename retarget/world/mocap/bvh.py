"""BVH motion capture (plain or gzip): the clip type and its parser.

Conventions handled here:

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

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pose_io.errors import InputError
from retarget.world.mocap.bvh_hierarchy import CHANNEL_RE, parse_hierarchy
from retarget.world.mocap.kinematics import MocapClip
from retarget.world.mocap.rotations import AXES, euler_matrices
from retarget.world.mocap.text import read_text


@dataclass(frozen=True, eq=False)
class BvhClip(MocapClip):
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
                axis, kind = CHANNEL_RE.match(name).groups()  # validated by the parser
                if kind.lower() == "rotation":
                    rot_cols.append(start + c)
                    rot_order += axis.upper()
                else:
                    pos[:, AXES[axis.upper()]] = self.motion[:, start + c]
                    has_pos = True
            rots[:, k] = euler_matrices(self.motion[:, rot_cols], rot_order) if rot_order else np.eye(3)
            if has_pos and self.absolute_positions[j]:
                trans[:, k] = pos
            else:
                trans[:, k] = self.offsets[j] + pos
        return rots, trans


def _header_value(line: str, key: str, path: str) -> str:
    head, _, value = line.partition(":")
    if head.strip().lower().replace(" ", "") != key:
        raise InputError(
            f"{path}: broken BVH motion header: expected '{key}:' but found {line.strip()[:40]!r}"
        )
    return value.strip()


def _motion_header(frames_line: str, time_line: str, source: str) -> tuple[int, float]:
    """``(frame count, seconds per frame)`` from the ``Frames:`` and ``Frame Time:`` lines."""
    frames_s = _header_value(frames_line, "frames", source)
    time_s = _header_value(time_line, "frametime", source)
    try:
        n_frames = int(frames_s)
        frame_time = float(time_s)
    except ValueError:
        raise InputError(
            f"{source}: broken BVH motion header: frames {frames_s!r}, frame time {time_s!r}"
        ) from None
    if n_frames <= 0:
        raise InputError(f"{source}: BVH declares {n_frames} frames")
    if not (math.isfinite(frame_time) and frame_time > 0):
        raise InputError(f"{source}: BVH frame time must be positive, got {time_s!r}")
    return n_frames, frame_time


def _is_float(tok: str) -> bool:
    try:
        float(tok)
    except ValueError:
        return False
    return True


def _parse_motion(section: str, total: int, source: str) -> tuple[float, np.ndarray]:
    """Frame time and the ``[T, total]`` float64 channel values of the text after ``MOTION``."""
    rest = section.lstrip("\r\n").split("\n", 2)
    if len(rest) < 2:
        raise InputError(f"{source}: truncated BVH: the motion header is incomplete")
    n_frames, frame_time = _motion_header(rest[0], rest[1], source)
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
                    f"{source}: wrong channel count: frame {i + 1} has {got} values, "
                    f"the hierarchy declares {total}"
                )
    try:
        motion = np.array(tokens, dtype=np.float64).reshape(n_frames, total)
    except ValueError:
        bad = next(t for t in tokens if not _is_float(t))
        raise InputError(f"{source}: non-numeric value {bad[:20]!r} in the BVH motion data") from None
    if not np.isfinite(motion).all():
        raise InputError(f"{source}: non-finite values in the BVH motion data")
    return frame_time, motion


def _absolute_positions(
    channels: Sequence[tuple[str, ...]], starts: np.ndarray, offsets: np.ndarray, motion: np.ndarray
) -> np.ndarray:
    """[N] bool: whether each joint's position channels replace its OFFSET (see the module docstring).

    Args:
        channels: per joint, its channel names.
        starts: [N] column of each joint's first channel.
        offsets: [N, 3] OFFSETs.
        motion: [T, C] channel values.
    """
    absolute = np.zeros(len(channels), dtype=bool)
    for j, chans in enumerate(channels):
        cols = [starts[j] + c for c, name in enumerate(chans) if name.lower().endswith("position")]
        if not cols:
            continue
        axes = [AXES[name[0].upper()] for c, name in enumerate(chans) if name.lower().endswith("position")]
        mean = np.zeros(3)
        mean[axes] = motion[:, cols].mean(axis=0)
        norm = float(np.linalg.norm(offsets[j]))
        absolute[j] = norm > 0 and float(mean @ offsets[j]) / norm > 0.5 * norm
    return absolute


def parse_bvh(text: str, source: str = "<string>") -> BvhClip:
    """Parse BVH text (see ``read_bvh``)."""
    match = re.search(r"^\s*MOTION\s*$", text, flags=re.MULTILINE)
    if match is None:
        raise InputError(f"{source}: not a BVH file (no MOTION section)")
    names, parents, offsets, channels = parse_hierarchy(text[: match.start()], source)
    counts = [len(c) for c in channels]
    total = int(sum(counts))
    if total == 0:
        raise InputError(f"{source}: BVH hierarchy has no channels")
    frame_time, motion = _parse_motion(text[match.end():], total, source)

    offsets_a = np.array(offsets, dtype=np.float64).reshape(-1, 3)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)
    return BvhClip(
        names=tuple(names),
        parents=np.array(parents, dtype=np.int64),
        offsets=offsets_a,
        channels=tuple(channels),
        channel_start=starts,
        frame_time=frame_time,
        motion=motion,
        absolute_positions=_absolute_positions(channels, starts, offsets_a, motion),
        source=source,
    )


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


__all__ = ["BvhClip", "parse_bvh", "read_bvh"]
