"""The joint tree of a mocap clip and its forward kinematics.

``MocapClip`` is the one declaration of a rig's hierarchy (joint ``names`` and ``parents``, parents
before children) shared by the readers (``bvh``, ``asf_amc``) and the motion world
(``retarget.world.rigs``). Each clip type only says how it makes its joints' local transforms; the walk
down the tree is written once, here.

This is not the canonical skeleton's tree (``retarget.world.skeleton.BONES``): a rig's tree comes from a
file, has as many joints as the file declares and is driven by rotations, while the world's is a fixed
18-joint tree of bone vectors; ``retarget.world.rigs`` maps the one onto the other.
"""

from __future__ import annotations

import abc
from collections.abc import Iterable, Sequence

import numpy as np


def ancestor_closure(parents: np.ndarray, joints: Iterable[int] | None) -> np.ndarray:
    """Sorted indices of ``joints`` and all their ancestors.

    Args:
        parents: [N] parent index per joint, -1 for a root.
        joints: the joints wanted; None for all.

    Returns:
        [K] int64 indices, ascending (so parents come before children when they do in ``parents``).
    """
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


class MocapClip(abc.ABC):
    """A motion-capture clip as a joint tree: what every reader gives and ``load_motion`` needs.

    Subclasses are frozen dataclasses that declare these attributes as fields and implement
    ``num_frames`` and ``local_transforms``; positions are in the file's own units and axes.

    Attributes:
        names: joint names, parents before children.
        parents: [N] int parent index per joint, -1 for a root.
        frame_time: seconds per frame.
        source: the file(s) it was read from, for messages.
    """

    names: tuple[str, ...]
    parents: np.ndarray
    frame_time: float
    source: str

    @property
    def fps(self) -> float:
        return 1.0 / self.frame_time

    @property
    @abc.abstractmethod
    def num_frames(self) -> int:
        """Number of frames T."""

    def index(self, name: str) -> int:
        """Index of joint ``name``; KeyError names the file."""
        try:
            return self.names.index(name)
        except ValueError:
            raise KeyError(f"{self.source or 'clip'}: no joint {name!r}") from None

    @abc.abstractmethod
    def local_transforms(self, joints: Sequence[int] | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Each joint's rotation and translation in its parent's frame, per frame.

        Args:
            joints: [K] indices to compute (default all).

        Returns:
            ``(rotations [T, K, 3, 3], translations [T, K, 3])``.
        """

    def global_transforms(self, joints: Iterable[int] | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Forward kinematics.

        Args:
            joints: indices wanted (their ancestors are computed too); default all.

        Returns:
            ``(rotations [T, N, 3, 3], positions [T, N, 3])`` in file units and axes; joints that were
            not needed are NaN.
        """
        idx = ancestor_closure(self.parents, joints)
        local_r, local_t = self.local_transforms(idx)
        return forward_kinematics(self.parents, local_r, local_t, idx)

    def global_positions(self, joints: Iterable[int] | None = None) -> np.ndarray:
        """[T, N, 3] world positions of the joints (all by default; file units and axes)."""
        return self.global_transforms(joints)[1]


__all__ = ["MocapClip", "ancestor_closure", "forward_kinematics"]
