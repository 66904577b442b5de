"""Characters, their sampling and 3D retargeting."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from retarget.world import (
    NAMED_CHARACTERS,
    WORLD_JOINTS,
    Motion3D,
    Skeleton,
    load_motion,
    make_skeleton,
    retarget_3d,
    sample_skeleton,
    skeleton_of,
)
from retarget.world.skeleton import bone_lengths, bone_vectors, rest_pose
from tests.retarget.world.humanoid import MOTIONBUILDER, humanoid_bvh

J = WORLD_JOINTS.index


def swinging_motion(skeleton: Skeleton, frames: int = 40, speed: float = 1.2) -> Motion3D:
    """A walking-like clip of ``skeleton``: arms and legs swing in the sagittal plane, the body moves +Z."""
    base = rest_pose(skeleton)
    out = np.repeat(base[None], frames, axis=0)
    t = np.arange(frames) / 30.0
    for side, phase in (("l", 0.0), ("r", np.pi)):
        ang = 0.5 * np.sin(2 * np.pi * t + phase)  # [T] radians about the X axis
        for root, chain in ((f"{side}_hip", (f"{side}_knee", f"{side}_ankle", f"{side}_big_toe")),
                            (f"{side}_shoulder", (f"{side}_elbow", f"{side}_wrist"))):
            a = ang if root.endswith("hip") else -ang
            c, s = np.cos(a), np.sin(a)
            for joint in chain:
                v = base[J(joint)] - base[J(root)]
                # Rotate about X: y' = c y - s z, z' = s y + c z.
                out[:, J(joint), 1] = base[J(root), 1] + c * v[1] - s * v[2]
                out[:, J(joint), 2] = base[J(root), 2] + s * v[1] + c * v[2]
    out[:, :, 2] += speed * t[:, None]
    out[:, :, 1] -= out[:, [J("l_ankle"), J("r_ankle"), J("l_big_toe"), J("r_big_toe")], 1].min(axis=1)[:, None]
    out[:, :, 1] += 0.02 * np.abs(np.sin(2 * np.pi * t))[:, None]  # a small hop: not always on the ground
    return Motion3D(out.astype(np.float32), 30.0, "swing")


def test_world_joints_contract() -> None:
    assert len(WORLD_JOINTS) == 18
    assert WORLD_JOINTS[:15] == (
        "nose", "neck", "r_shoulder", "r_elbow", "r_wrist", "l_shoulder", "l_elbow", "l_wrist", "mid_hip",
        "r_hip", "r_knee", "r_ankle", "l_hip", "l_knee", "l_ankle",
    )
    assert WORLD_JOINTS[15:] == ("l_big_toe", "r_big_toe", "head")


def test_make_skeleton_hits_the_height_and_rest_pose_stands() -> None:
    for h in (1.1, 1.4, 1.75, 2.05):
        skel = make_skeleton(h, legs=1.1, arms=0.9)
        assert skel.height == pytest.approx(h, rel=1e-9)
        pose = rest_pose(skel)
        assert pose[:, 1].min() == pytest.approx(0.0, abs=1e-12)
        np.testing.assert_allclose(bone_lengths(pose), skel.array, atol=1e-12)
        # The top of the skull (not a joint) is at the height by construction.
        top = pose[J("head"), 1] + 1.1 * skel.length("nose") + 0.5 * skel.length("l_big_toe")
        assert top == pytest.approx(h, abs=1e-9)


def test_sampled_skeletons_cover_human_ranges_independently() -> None:
    rng = np.random.default_rng(0)
    skels = [sample_skeleton(rng) for _ in range(600)]
    heights = np.array([s.height for s in skels])
    assert heights.min() >= 1.1 - 1e-9 and heights.max() <= 2.05 + 1e-9
    assert heights.min() < 1.2 and heights.max() > 1.95
    for s in skels:
        d = s.as_dict()
        assert d["l_knee"] == d["r_knee"] and d["l_elbow"] == d["r_elbow"]  # symmetric
    adults = [s for s in skels if s.height > 1.6]
    legs = np.array([s.leg_length / s.height for s in adults])
    arms = np.array([(s.length("l_elbow") + s.length("l_wrist")) / s.height for s in adults])
    shoulders = np.array([s.length("l_shoulder") / s.height for s in adults])
    assert legs.std() > 0.01 and arms.std() > 0.01 and shoulders.std() > 0.005
    # Independent parts: proportions are not tied to one another.
    assert abs(np.corrcoef(legs, arms)[0, 1]) < 0.35
    assert abs(np.corrcoef(arms, shoulders)[0, 1]) < 0.35
    # Same seed, same characters.
    again = sample_skeleton(np.random.default_rng(0))
    assert again == skels[0]


def test_named_characters_differ() -> None:
    assert {"average", "tall_long_legs", "short_stocky", "child"} <= set(NAMED_CHARACTERS)
    avg, tall = NAMED_CHARACTERS["average"], NAMED_CHARACTERS["tall_long_legs"]
    stocky, child = NAMED_CHARACTERS["short_stocky"], NAMED_CHARACTERS["child"]
    assert tall.height > 1.95 and child.height < 1.25 and stocky.height < avg.height
    assert tall.leg_length / tall.height > avg.leg_length / avg.height
    assert stocky.length("l_shoulder") / stocky.height > avg.length("l_shoulder") / avg.height
    assert child.length("nose") / child.height > avg.length("nose") / avg.height
    assert all(name == skel.name for name, skel in NAMED_CHARACTERS.items())


def test_retarget_on_own_skeleton_is_identity() -> None:
    motion = swinging_motion(make_skeleton(1.7))
    same = retarget_3d(motion, skeleton_of(motion))
    np.testing.assert_allclose(same.positions, motion.positions, atol=1e-5)


def test_retarget_loaded_clip_on_own_skeleton_is_identity(tmp_path: Path) -> None:
    """A clip read through a rig mapping (a walk written as BVH here), not one built in the world's joints."""
    path = tmp_path / "walk.bvh"
    path.write_text(humanoid_bvh(MOTIONBUILDER, frames=60, step=4.0, swing=25.0, bow=10.0))
    motion = load_motion(path)
    same = retarget_3d(motion, skeleton_of(motion))
    np.testing.assert_allclose(same.positions, motion.positions, atol=1e-5)


def test_retarget_changes_lengths_keeps_directions_and_feet() -> None:
    source = make_skeleton(1.75)
    motion = swinging_motion(source)
    target = NAMED_CHARACTERS["tall_long_legs"]
    out = retarget_3d(motion, target)
    lengths = bone_lengths(out.positions.astype(np.float64))
    np.testing.assert_allclose(lengths, np.broadcast_to(target.array, lengths.shape), rtol=1e-5)
    # Directions per bone and frame are unchanged.
    ua = bone_vectors(motion.positions.astype(np.float64))
    ub = bone_vectors(out.positions.astype(np.float64))
    ua /= np.linalg.norm(ua, axis=-1, keepdims=True)
    ub /= np.linalg.norm(ub, axis=-1, keepdims=True)
    np.testing.assert_allclose(ua, ub, atol=1e-5)
    # Root travel scales with the legs; the lowest foot scales too (0 stays 0).
    ratio = target.leg_length / source.leg_length
    travel_a = motion.positions[-1, J("mid_hip"), 2] - motion.positions[0, J("mid_hip"), 2]
    travel_b = out.positions[-1, J("mid_hip"), 2] - out.positions[0, J("mid_hip"), 2]
    assert travel_b == pytest.approx(ratio * travel_a, rel=1e-5)
    feet = [J(n) for n in ("l_ankle", "r_ankle", "l_big_toe", "r_big_toe")]
    low_a = motion.positions[:, feet, 1].min(axis=1)
    low_b = out.positions[:, feet, 1].min(axis=1)
    np.testing.assert_allclose(low_b, ratio * low_a, atol=1e-5)
    assert low_b.min() == pytest.approx(0.0, abs=1e-5)


def test_retarget_without_foot_fix_differs_when_proportions_change() -> None:
    motion = swinging_motion(make_skeleton(1.75))
    target = make_skeleton(1.75, thigh_shin=1.3, feet=1.3)
    fixed = retarget_3d(motion, target)
    raw = retarget_3d(motion, target, keep_feet_on_ground=False)
    assert np.abs(fixed.positions - raw.positions).max() > 1e-3
