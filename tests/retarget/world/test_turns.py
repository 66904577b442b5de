"""retarget.world.turns: whole-body turns in 3D, and how far a window turns."""

from __future__ import annotations

import numpy as np
import pytest

from retarget.world.skeleton import WORLD_JOINTS
from retarget.world.turns import Turn, apply_turn, draw_turn, facing_change, turn_angles

ROOT = WORLD_JOINTS.index("mid_hip")


def walk(frames: int = 40, speed: float = 0.02) -> np.ndarray:
    """[T, 18, 3] a stiff body facing +Z (its left at +X) gliding forward ``speed`` metres per frame."""
    base = np.zeros((len(WORLD_JOINTS), 3))
    for j, name in enumerate(WORLD_JOINTS):
        base[j] = (0.2 if name.startswith("l_") else -0.2 if name.startswith("r_") else 0.0, 1.0 + 0.03 * j, 0.0)
    pos = np.repeat(base[None], frames, axis=0)
    pos[..., 2] += speed * np.arange(frames)[:, None]
    return pos.astype(np.float32)


def test_a_turn_rotates_the_body_and_bends_its_path():
    pos = walk()
    turned = apply_turn(pos, Turn(90.0, start=10, duration=10))
    assert turned.dtype == np.float32 and turned.shape == pos.shape
    np.testing.assert_allclose(turned[:11], pos[:11], atol=1e-6)  # nothing moves before the turn
    # Bones keep their lengths and heights.
    np.testing.assert_allclose(np.linalg.norm(turned - turned[:, ROOT : ROOT + 1], axis=-1),
                               np.linalg.norm(pos - pos[:, ROOT : ROOT + 1], axis=-1), atol=1e-5)  # fmt: skip
    np.testing.assert_allclose(turned[..., 1], pos[..., 1], atol=1e-6)
    assert facing_change(pos) < 1e-3 and facing_change(turned) == pytest.approx(90.0, abs=1e-3)
    # After the turn the body faces +X and walks on that way (the path turns with it).
    step = np.diff(turned[20:, ROOT], axis=0)
    np.testing.assert_allclose(step, np.tile([0.02, 0.0, 0.0], (len(step), 1)), atol=1e-6)


def test_turn_angles_rise_smoothly_and_either_way():
    angles = turn_angles(Turn(-360.0, start=5, duration=20), 40)
    assert angles[:6].tolist() == [0.0] * 6 and angles[25:] == pytest.approx(np.full(15, -2 * np.pi))
    assert (np.diff(angles) <= 1e-12).all()  # monotone
    assert facing_change(apply_turn(walk(), Turn(-360.0, 5, 20))) == pytest.approx(360.0, abs=1e-2)


def test_drawn_turns_stay_in_range_and_inside_the_window():
    rng = np.random.default_rng(0)
    turns = [draw_turn(rng, 64) for _ in range(500)]
    angles = np.array([t.angle_deg for t in turns])
    assert (90 <= np.abs(angles)).all() and (np.abs(angles) <= 360).all()
    assert 0.4 < (angles > 0).mean() < 0.6  # either way
    assert all(t.start >= 0 and t.start + t.duration <= 63 + 1e-9 and t.duration >= 0.3 * 63 - 1e-9 for t in turns)
    # A stack of windows is measured window by window.
    both = np.stack([walk(), apply_turn(walk(), turns[0])])
    assert facing_change(both) == pytest.approx([0.0, abs(turns[0].angle_deg)], abs=1e-2)
