"""The joint tree shared by the mocap readers and its forward kinematics."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pytest

from retarget.world.mocap import AcclaimClip, BvhClip, MocapClip, forward_kinematics
from retarget.world.mocap.kinematics import ancestor_closure
from retarget.world.mocap.rotations import axis_rotations

PARENTS = np.array([-1, 0, 1, 0])  # a root with a two-joint chain and a single child


def test_ancestor_closure() -> None:
    assert ancestor_closure(PARENTS, None).tolist() == [0, 1, 2, 3]
    assert ancestor_closure(PARENTS, [2]).tolist() == [0, 1, 2]
    assert ancestor_closure(PARENTS, [3, 1]).tolist() == [0, 1, 3]


def test_forward_kinematics_known_values() -> None:
    rz = axis_rotations(2, 90.0)
    local_r = np.stack([rz, np.eye(3), np.eye(3)])[None]  # [T=1, K=3, 3, 3]
    local_t = np.array([[[1.0, 0, 0], [1, 0, 0], [0, 1, 0]]])  # [1, 3, 3]
    rot, pos = forward_kinematics(PARENTS, local_r, local_t, np.array([0, 1, 2]))
    # The root's quarter turn about Z takes +X to +Y and +Y to -X for every child.
    np.testing.assert_allclose(pos[0, :3], [[1, 0, 0], [1, 1, 0], [0, 1, 0]], atol=1e-12)
    np.testing.assert_allclose(rot[0, :3], np.broadcast_to(rz, (3, 3, 3)), atol=1e-12)
    assert np.isnan(pos[0, 3]).all() and np.isnan(rot[0, 3]).all()  # not asked for


@dataclass(frozen=True, eq=False)
class Chain(MocapClip):
    """A clip whose joints are offset by one unit along X from their parent and never turn."""

    names: tuple[str, ...]
    parents: np.ndarray
    frame_time: float = 0.5
    source: str = "chain"

    @property
    def num_frames(self) -> int:
        return 2

    def local_transforms(self, joints: Sequence[int] | None = None) -> tuple[np.ndarray, np.ndarray]:
        k = len(self.names) if joints is None else len(joints)
        rot = np.broadcast_to(np.eye(3), (2, k, 3, 3)).copy()
        trans = np.zeros((2, k, 3))
        trans[..., 0] = 1.0
        return rot, trans


def test_a_clip_only_supplies_local_transforms() -> None:
    clip = Chain(("a", "b", "c", "d"), PARENTS)
    assert clip.fps == 2.0 and clip.index("c") == 2
    np.testing.assert_allclose(clip.global_positions()[1, :, 0], [1, 2, 3, 2])
    assert np.isnan(clip.global_positions([1])[:, 2:]).all()
    with pytest.raises(KeyError, match="chain: no joint 'e'"):
        clip.index("e")
    assert issubclass(BvhClip, MocapClip) and issubclass(AcclaimClip, MocapClip)
