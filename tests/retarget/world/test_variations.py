"""retarget.world.variations: upper/lower-body splicing and joint-angle noise in 3D."""

from __future__ import annotations

import numpy as np
import pytest

from retarget.world.skeleton import (
    BONE_NAMES,
    WORLD_JOINTS,
    Skeleton,
    assemble,
    bone_lengths,
    bone_vectors,
    rest_pose,
)
from retarget.world.turns import Turn, apply_turn
from retarget.world.variations import UPPER_BONES, bend, draw_bend, splice

J = {name: i for i, name in enumerate(WORLD_JOINTS)}
LEGS = [J[n] for n in ("mid_hip", "l_hip", "r_hip", "l_knee", "r_knee", "l_ankle", "r_ankle", "l_big_toe",
                       "r_big_toe")]  # fmt: skip
B = {name: i for i, name in enumerate(BONE_NAMES)}


def moving(seed: int, frames: int = 48) -> np.ndarray:
    """[T, 18, 3] a body whose every bone swings differently (seeded) while its root walks."""
    rng = np.random.default_rng(seed)
    rest = rest_pose(Skeleton(tuple(rng.uniform(0.1, 0.5, len(BONE_NAMES)))))
    vectors = np.repeat(bone_vectors(rest)[None], frames, axis=0)  # [T, 17, 3]
    phase = np.arange(frames)[:, None] * rng.uniform(0.05, 0.2, len(BONE_NAMES))
    angle = 0.5 * np.sin(phase + rng.uniform(0, 6, len(BONE_NAMES)))  # [T, 17] radians about +X
    y, z = vectors[..., 1].copy(), vectors[..., 2].copy()
    vectors[..., 1], vectors[..., 2] = np.cos(angle) * y - np.sin(angle) * z, np.sin(angle) * y + np.cos(angle) * z
    pos = np.zeros((frames, len(WORLD_JOINTS), 3))
    pos[:, J["mid_hip"]] = rest[J["mid_hip"]] + np.outer(np.arange(frames), [0.0, 0.0, 0.02])
    return assemble(pos[:, J["mid_hip"]], vectors)


def test_a_splice_keeps_the_legs_and_takes_the_upper_body_turned_to_the_pelvis():
    lower, upper = moving(0), moving(1)
    # the same character: give the upper window the lower's bone lengths
    vec = bone_vectors(upper)
    vec *= (bone_lengths(lower)[0] / np.linalg.norm(vec, axis=-1))[..., None]
    upper = assemble(upper[:, J["mid_hip"]], vec)
    out = splice(lower, upper)
    assert out.dtype == np.float32 and out.shape == lower.shape
    np.testing.assert_allclose(out[:, LEGS], lower[:, LEGS], atol=1e-5)  # legs and root path are the lower's
    np.testing.assert_allclose(bone_lengths(out), bone_lengths(lower), atol=1e-5)
    up = list(UPPER_BONES)
    np.testing.assert_allclose(bone_vectors(out)[:, up, 1], bone_vectors(upper)[:, up, 1], atol=1e-5)
    assert not np.allclose(out[:, J["l_wrist"]], lower[:, J["l_wrist"]], atol=1e-3)
    # An upper window that is the lower one turned by 90 degrees is turned back onto the pelvis: the identity.
    turned = apply_turn(lower, Turn(90.0, start=0, duration=1))
    np.testing.assert_allclose(splice(lower, turned), lower, atol=1e-5)
    np.testing.assert_allclose(splice(lower, lower), lower, atol=1e-6)
    with pytest.raises(ValueError, match="splice"):
        splice(lower, upper[:10])


def test_a_bend_rotates_the_upper_chain_about_its_joints_and_leaves_the_legs():
    pos = moving(2)
    t = len(pos)
    np.testing.assert_allclose(bend(pos, np.zeros((t, len(UPPER_BONES), 3))), pos, atol=1e-6)
    rot = np.zeros((t, len(UPPER_BONES), 3))
    rot[:, UPPER_BONES.index(B["r_shoulder"])] = [0.0, 0.0, 0.3]  # the right shoulder only
    out = bend(pos, rot)
    np.testing.assert_allclose(out[:, LEGS], pos[:, LEGS], atol=1e-6)
    np.testing.assert_allclose(bone_lengths(out), bone_lengths(pos), atol=1e-5)
    np.testing.assert_allclose(out[:, J["l_wrist"]], pos[:, J["l_wrist"]], atol=1e-6)  # the other arm stays
    assert not np.allclose(out[:, J["r_wrist"]], pos[:, J["r_wrist"]], atol=1e-3)
    # The shoulder's rotation carries the elbow and wrist: the elbow's angle is unchanged.
    def elbow(p):
        v = bone_vectors(p)
        a, b = v[:, B["r_elbow"]], v[:, B["r_wrist"]]
        return np.sum(a * b, -1) / np.linalg.norm(a, axis=-1) / np.linalg.norm(b, axis=-1)

    np.testing.assert_allclose(elbow(out), elbow(pos), atol=1e-5)
    with pytest.raises(ValueError, match="rotvecs"):
        bend(pos, rot[:, :3])


def test_bend_noise_is_smooth_seeded_and_of_its_size():
    a = draw_bend(np.random.default_rng(0), 64, 8.0)
    np.testing.assert_array_equal(a, draw_bend(np.random.default_rng(0), 64, 8.0))
    assert a.shape == (64, len(UPPER_BONES), 3)
    deg = np.degrees(a)
    angle = np.linalg.norm(deg, axis=-1)  # each bone's rotation angle
    assert 5.0 < np.sqrt((angle**2).mean()) < 11.0 and angle.max() < 8.0 * 3.5
    assert np.abs(np.diff(deg, axis=0)).max() < 4.0  # degrees per frame: a slow drift, not jitter
    np.testing.assert_array_equal(draw_bend(np.random.default_rng(1), 64, 0.0), 0.0)
    with pytest.raises(ValueError):
        draw_bend(np.random.default_rng(0), 64, -1.0)
