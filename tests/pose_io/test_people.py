import numpy as np
import pytest

from pose_io import Detections, InputError, follow_person
from pose_io.people import pose_distance, prominence

J = 25


def figure(x: float, y: float, height: float = 100.0, conf: float = 0.9) -> np.ndarray:
    """[J, 3] a stick figure of the given height with its top-left near (x, y)."""
    rng = np.random.default_rng(0)  # the same body shape everywhere
    xy = np.array([x, y]) + rng.uniform(0, 1, (J, 2)) * [height * 0.4, height]
    return np.concatenate([xy, np.full((J, 1), conf)], axis=1).astype(np.float32)


def detections(frames: list[list[np.ndarray]], **kw) -> Detections:
    people = tuple(np.stack(f) if f else np.zeros((0, J, 3), np.float32) for f in frames)
    return Detections(people, "body25", source="test", **kw)


def test_default_is_the_most_prominent_person_not_the_first():
    small, big = figure(10, 10, height=50), figure(300, 10, height=200)
    result = follow_person(detections([[small, big], [small, big]]))
    assert result.chosen.tolist() == [1, 1]
    assert prominence(big) > prominence(small)
    # Low confidence shrinks prominence.
    faint_big = figure(300, 10, height=200, conf=0.05)
    assert follow_person(detections([[small, faint_big]])).chosen.tolist() == [0]


def test_person_k_and_out_of_range():
    a, b = figure(10, 10), figure(300, 10)
    d = detections([[], [a, b], [b, a]])
    result = follow_person(d, person=0)
    assert result.start == 1 and result.chosen.tolist() == [-1, 0, 1]
    assert np.isnan(result.joints[0]).all()
    with pytest.raises(InputError, match="person 2 does not exist; frame 1 has 2 people"):
        follow_person(d, person=2)


def test_nearest_match_follows_a_moving_person_through_reordering():
    frames = []
    for t in range(10):
        mover = figure(100 + 5 * t, 50)
        other = figure(400, 50, height=150)
        frames.append([other, mover] if t % 2 else [mover, other])
    result = follow_person(detections(frames), person=0)
    assert result.chosen.tolist() == [0, 1] * 5
    assert not result.lost


def test_gate_gives_missing_frames_and_tracking_recovers():
    a = figure(100, 100)
    far = figure(600, 100)
    frames = [[a], [a + [2, 0, 0]], [far], [far], [a + [4, 0, 0]], [a + [5, 0, 0]]]
    result = follow_person(detections(frames))
    assert result.lost == (2, 3)
    assert np.isnan(result.joints[2:4]).all() and (result.confidence[2:4] == 0).all()
    assert result.chosen.tolist() == [0, 0, -1, -1, 0, 0]


def test_distance_uses_joints_visible_in_both():
    a = figure(0, 0)
    b = a.copy()
    b[:, :2] += 3.0
    b[5:, 2] = 0.0
    known = np.ones(J, bool)
    assert pose_distance(a[:, :2], known, b) == pytest.approx(3 * np.sqrt(2), rel=1e-5)
    assert pose_distance(a[:, :2], np.zeros(J, bool), b) == np.inf


def test_identities_are_followed_when_given():
    a, b = figure(100, 100), figure(110, 100)
    ids = (np.array([5, 9]), np.array([9, 5]), np.array([9]))
    result = follow_person(detections([[a, b], [a, b], [a]], ids=ids), person=0)
    assert result.chosen.tolist() == [0, 1, -1] and result.lost == (2,)


def test_no_person_anywhere():
    with pytest.raises(InputError, match="no person in any frame"):
        follow_person(detections([[], []]))


def test_counts():
    a = figure(0, 0)
    assert detections([[a, a], [], [a]]).counts.tolist() == [2, 0, 1]
