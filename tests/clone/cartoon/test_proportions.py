import numpy as np
import pytest

from clone.cartoon.proportions import displacement, held_limbs, hold_lengths, proportion_error, tree_order
from pose_io.measures import limb_lengths
from retarget.inference.tracks import filled_body15
from retarget.network.preprocess import LAYOUT, ROOT_INDEX
from tests.figures import walking_figure


@pytest.fixture
def joints():
    return filled_body15(walking_figure(20, seed=5))  # [20, 15, 2]


def test_tree_order_places_parents_first():
    order = tree_order()
    placed = {ROOT_INDEX}
    for parent, child, _ in order:
        assert parent in placed and child not in placed
        placed.add(child)
    assert len(order) == len(LAYOUT.limbs) and len(placed) == len(LAYOUT)


def test_held_limbs_get_their_length_in_every_frame_and_widths_keep_their_vector(joints):
    targets = np.linspace(20.0, 80.0, len(LAYOUT.limbs))
    rest = joints[0]
    held = hold_lengths(joints, np.where(held_limbs(), targets, np.nan), rest)
    lengths = limb_lengths(held)  # [T, L]
    np.testing.assert_allclose(lengths[:, held_limbs()], np.broadcast_to(targets[held_limbs()], (20, 10)), rtol=1e-9)
    np.testing.assert_allclose(held[:, ROOT_INDEX], joints[:, ROOT_INDEX])
    for i, (a, b) in enumerate(LAYOUT.limbs):
        before = joints[:, LAYOUT.index(b)] - joints[:, LAYOUT.index(a)]  # [T, 2]
        after = held[:, LAYOUT.index(b)] - held[:, LAYOUT.index(a)]
        if held_limbs()[i]:  # the same direction
            np.testing.assert_allclose(_unit(after), _unit(before), atol=1e-9)
        else:  # a width: the same vector
            np.testing.assert_allclose(after, before, atol=1e-9)


def _unit(vectors: np.ndarray) -> np.ndarray:
    return vectors / np.linalg.norm(vectors, axis=-1, keepdims=True)


def test_a_limb_without_length_takes_the_rest_direction(joints):
    collapsed = joints.copy()
    elbow, wrist = LAYOUT.index("l_elbow"), LAYOUT.index("l_wrist")
    collapsed[:, wrist] = collapsed[:, elbow]
    rest = np.zeros((15, 2))
    rest[wrist] = rest[elbow] + [0.0, 1.0]  # hanging down
    lengths = np.full(len(LAYOUT.limbs), np.nan)
    lengths[LAYOUT.limbs.index(("l_elbow", "l_wrist"))] = 30.0
    held = hold_lengths(collapsed, lengths, rest)
    np.testing.assert_allclose(held[:, wrist] - held[:, elbow], np.broadcast_to([0.0, 30.0], (20, 2)))


def test_error_is_zero_after_the_fix_and_the_fix_reports_its_move(joints):
    targets = limb_lengths(joints[:1])[0] * 1.3
    before = proportion_error(joints, targets, 300.0)
    held = hold_lengths(joints, np.where(held_limbs(), targets, np.nan), joints[0])
    after = proportion_error(held, targets, 300.0)
    assert before["mean_pct"] > 1.0 and after["mean_pct"] < 1e-9
    assert set(after["per_limb_pct"]) == {f"{a}-{b}" for (a, b), h in zip(LAYOUT.limbs, held_limbs()) if h}
    moved = displacement(joints, held, 300.0)
    assert 0 < moved["mean_pct"] < moved["max_pct"]
    assert displacement(joints, joints, 300.0) == {"mean_pct": 0.0, "max_pct": 0.0}
