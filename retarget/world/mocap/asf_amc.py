"""Acclaim motion capture, as in the CMU database: an ASF skeleton (``asf``) driven by an AMC motion.

A bone's rotation in its parent's frame is ``C @ M @ C^T``, with ``C`` its ASF ``axis`` frame and ``M``
the rotation of its AMC degrees of freedom (Acclaim's fixed-axis order, ``rotations.acclaim_rotation``);
a bone starts where its parent ends.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pose_io.errors import InputError
from retarget.world.mocap.asf import AsfSkeleton, read_asf
from retarget.world.mocap.kinematics import MocapClip
from retarget.world.mocap.rotations import AXES, acclaim_rotation
from retarget.world.mocap.text import read_text

# AMC degree-of-freedom name -> axis column (translations and bone lengths are ignored).
_DOF_AXES = {"rx": 0, "ry": 1, "rz": 2}

# One AMC frame: bone name -> its values in the ASF's dof order.
_Frame = dict[str, list[float]]


@dataclass(frozen=True, eq=False)
class AcclaimClip(MocapClip):
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

    def local_transforms(self, joints: Sequence[int] | None = None) -> tuple[np.ndarray, np.ndarray]:
        """``L_b = C_b @ M_b @ C_b^T``, translated by the parent's bone vector (the root: its path).

        Args:
            joints: indices to compute (default all).

        Returns:
            ``(rotations [T, K, 3, 3], translations [T, K, 3])`` in ASF units and axes.
        """
        idx = np.arange(len(self.names)) if joints is None else np.asarray(joints, dtype=np.int64)
        c = self.axis_rotations[idx]
        # [T, K, 3, 3]: the bone's own rotation expressed in its parent's frame.
        local_r = c[None] @ self.dof_rotations[:, idx] @ np.swapaxes(c, -1, -2)[None]
        local_t = np.zeros((self.num_frames, len(idx), 3))
        for k, j in enumerate(idx):
            p = int(self.parents[j])
            if p < 0:
                local_t[:, k] = self.root_positions
            else:
                # The parent's bone vector is fixed in world axes at rest, so in the parent's frame it is
                # the rest vector itself.
                local_t[:, k] = self.vectors[p]
        return local_r, local_t


def _read_amc_frames(path: str | Path) -> list[_Frame]:
    """Every frame of an AMC file, in file order; a cut-off last frame number is dropped."""
    src = str(path)
    frames: list[_Frame] = []
    for raw in read_text(path).splitlines():
        line = raw.strip()
        if not line or line.startswith(("#", ":")):
            continue
        parts = line.split()
        if len(parts) == 1 and parts[0].isdigit():
            frames.append({})
            continue
        if not frames:
            raise InputError(f"{src}: not an AMC motion (data before the first frame number)")
        try:
            values = [float(v) for v in parts[1:]]
        except ValueError:
            raise InputError(f"{src}: non-numeric value in line {line[:40]!r}") from None
        if not all(math.isfinite(v) for v in values):
            raise InputError(f"{src}: non-finite value in line {line[:40]!r}")
        frames[-1][parts[0]] = values
    if not frames:
        raise InputError(f"{src}: AMC motion has no frames")
    if not frames[-1]:
        frames.pop()  # a trailing frame number with no data (cut-off file)
    return frames


def _root_motion(frames: list[_Frame], skel: AsfSkeleton, src: str) -> tuple[np.ndarray, np.ndarray]:
    """Root translation [T, 3] and rotation M [T, 3, 3] from the AMC root lines, in the ASF's order."""
    order = skel.root.order
    try:
        values = np.array([f["root"] for f in frames], dtype=np.float64)
    except KeyError:
        raise InputError(f"{src}: a frame has no root line") from None
    except ValueError:
        raise InputError(f"{src}: root lines have different lengths") from None
    if values.ndim != 2 or values.shape[1] != len(order):
        raise InputError(f"{src}: root lines must have {len(order)} values ({' '.join(order)})")
    t = len(frames)
    pos = np.zeros((t, 3))
    for k, c in enumerate(order):
        if c.startswith("T"):
            pos[:, AXES[c[1]]] = values[:, k]
    pos += skel.root.position
    rot = np.zeros((t, 3))
    for k, c in enumerate(order):
        if c.startswith("R"):
            rot[:, AXES[c[1]]] = skel.degrees(values[:, k])
    return pos, acclaim_rotation(rot, skel.root.axis)


def _dof_values(frames: list[_Frame], name: str, dofs: list[str], src: str) -> np.ndarray:
    """[T, 3] one bone's angles about x, y, z (file units; 0 for axes it lacks and frames omitting it)."""
    vals = np.zeros((len(frames), 3))
    for i, f in enumerate(frames):
        v = f.get(name)
        if v is None:
            continue
        if len(v) != len(dofs):
            raise InputError(
                f"{src}: frame {i + 1}: bone {name} has {len(v)} values, the ASF gives {len(dofs)} dof"
            )
        for d, val in zip(dofs, v):
            ax = _DOF_AXES.get(d.lower())
            if ax is not None:
                vals[i, ax] = val
    return vals


def _dof_rotations(
    frames: list[_Frame], skel: AsfSkeleton, root_rotation: np.ndarray, src: str
) -> np.ndarray:
    """[T, N, 3, 3] rotation M of every joint: the root's, each bone's from its dof, identity elsewhere."""
    out = np.broadcast_to(np.eye(3), (len(frames), len(skel.names), 3, 3)).copy()
    out[:, 0] = root_rotation
    for j, name in enumerate(skel.names):
        bone = skel.bones.get(name)
        if bone is None or not bone.dof:
            continue
        vals = _dof_values(frames, name, bone.dof, src)
        out[:, j] = acclaim_rotation(skel.degrees(vals), bone.axis_order)
    return out


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
    if not (math.isfinite(fps) and fps > 0):
        raise InputError(f"{amc_src}: fps must be a positive number, got {fps}")
    skel = read_asf(asf_path)
    frames = _read_amc_frames(amc_path)
    unknown = sorted({k for f in frames for k in f if k != "root" and k not in skel.bones})
    if unknown:
        raise InputError(f"{amc_src}: bones not in {Path(asf_src).name}: {', '.join(unknown[:5])}")
    root_pos, root_rot = _root_motion(frames, skel, amc_src)
    return AcclaimClip(
        names=tuple(skel.names),
        parents=np.array(skel.parents, dtype=np.int64),
        vectors=skel.vectors,
        axis_rotations=skel.axis_rotations,
        dof_rotations=_dof_rotations(frames, skel, root_rot, amc_src),
        root_positions=root_pos,
        frame_time=1.0 / fps,
        source=f"{asf_src} + {amc_src}",
    )


__all__ = ["AcclaimClip", "read_asf_amc"]
