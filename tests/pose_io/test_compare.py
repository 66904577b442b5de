"""pose_io.compare: the pose error and PCK, the root-aligned pose error, the placement error and the facing check."""

from __future__ import annotations

import numpy as np
import pytest

from pose_io import BODY15, BODY25, InputError
from pose_io import compare as m
from tests.pose_io.test_measures import HEIGHT, J, stand


def test_root_aligned_subtracts_and_drops_the_root_by_name():
    joints = stand(3) + [7.0, -2.0]
    aligned = m.root_aligned(joints)
    assert aligned.shape == (3, 14, 2)
    names = [n for n in BODY15.joints if n != "mid_hip"]
    np.testing.assert_allclose(aligned[:, names.index("nose")], [[0.0, -80.0]] * 3)  # 80 px above MidHip
    np.testing.assert_allclose(m.root_aligned(joints + [50.0, 9.0]), aligned)  # placement is gone
    body25 = np.zeros((2, 25, 2))
    body25[:, BODY25.index("mid_hip")] = [10.0, 20.0]
    assert m.root_aligned(body25, "body25")[0, BODY25.index("nose")].tolist() == [-10.0, -20.0]
    missing = joints.copy()
    missing[1, J("mid_hip")] = np.nan
    assert np.isnan(m.root_aligned(missing)[1]).all() and not np.isnan(m.root_aligned(missing)[0]).any()
    with pytest.raises(InputError, match="root-aligned pose"):
        m.root_aligned(np.zeros((3, 25, 2)))


def test_aligned_pose_error_ignores_placement_and_sees_proportions():
    truth = stand(4)
    assert m.aligned_pose_error(truth + [30.0, -12.0], truth, HEIGHT)["rmse_pct"] == pytest.approx(0.0, abs=1e-12)
    assert m.pose_error(truth + [30.0, -12.0], truth, HEIGHT)["rmse_pct"] > 15.0  # the placed error sees it
    root = truth[:, J("mid_hip") : J("mid_hip") + 1]
    bigger = root + 1.2 * (truth - root)  # the same pose 20 % larger about MidHip
    local = np.delete(truth - root, J("mid_hip"), axis=1)
    expected = 100 * np.sqrt(np.mean(np.sum((0.2 * local / HEIGHT) ** 2, axis=-1)))
    err = m.aligned_pose_error(bigger, truth, HEIGHT)
    assert err["rmse_pct"] == pytest.approx(expected)
    assert set(err) == {"mse", "rmse_pct", "pck_0.05", "pck_0.1"}


def test_root_distance_per_frame():
    truth = stand(3)
    pred = truth + np.array([[0.0, 0.0], [3.0, 4.0], [0.0, 16.0]])[:, None]  # [T, 1, 2] per-frame shifts
    pred[2, J("nose")] += 100.0  # other joints do not count
    np.testing.assert_allclose(m.root_distance(pred, truth, 10.0), [0.0, 0.5, 1.6])
    pred[0, J("mid_hip")] = np.nan
    assert np.isnan(m.root_distance(pred, truth, 10.0)[0])
    with pytest.raises(InputError, match="does not match"):
        m.root_distance(stand(3), stand(4), 10.0)
    with pytest.raises(InputError, match="height must be positive"):
        m.root_distance(stand(3), stand(3), 0.0)


def _facing(offsets: list[float]) -> np.ndarray:
    """Standing poses whose nose is ``offset`` heights right of the neck, one frame per offset."""
    joints = stand(len(offsets))
    joints[:, J("nose"), 0] = joints[:, J("neck"), 0] + np.asarray(offsets) * HEIGHT
    return joints


def test_facing_offset_and_same_facing():
    truth = _facing([-0.03, -0.03, 0.03, 0.002, -0.03])
    np.testing.assert_allclose(m.facing_offset(truth, HEIGHT), [-0.03, -0.03, 0.03, 0.002, -0.03])
    pred = _facing([-0.02, 0.02, 0.01, 0.05, np.nan])
    same = m.same_facing(pred, truth, HEIGHT, HEIGHT)
    np.testing.assert_array_equal(same[:3], [1.0, 0.0, 1.0])
    assert np.isnan(same[3]) and np.isnan(same[4])  # the truth shows no side / the prediction has no nose
    # Only signs count: the prediction may be another size in another image.
    np.testing.assert_array_equal(m.same_facing(pred * 3.0, truth, 3 * HEIGHT, HEIGHT)[:3], [1.0, 0.0, 1.0])
    with pytest.raises(InputError, match="frames"):
        m.same_facing(_facing([0.1]), truth, HEIGHT, HEIGHT)



def test_pose_error_known_values():
    truth = stand(4)
    pred = truth.copy()
    pred[:, J("nose"), 0] += 0.08 * HEIGHT  # one joint of 15 off by 8 % of the height
    err = m.pose_error(pred, truth, HEIGHT)
    assert set(err) == {"mse", "rmse_pct", "pck_0.05", "pck_0.1"}
    assert err["mse"] == pytest.approx(0.08**2 / 30)  # over frames, joints and both coordinates
    assert err["rmse_pct"] == pytest.approx(np.sqrt(0.08**2 / 15) * 100)
    assert err["pck_0.05"] == pytest.approx(14 / 15) and err["pck_0.1"] == 1.0
    assert m.pose_error(truth, truth, HEIGHT) == {"mse": 0.0, "rmse_pct": 0.0, "pck_0.05": 1.0, "pck_0.1": 1.0}


def test_pose_error_leaves_missing_joints_out():
    truth = stand(2)
    pred = truth.copy()
    pred[:, J("nose")] = np.nan
    truth[0, J("neck")] = np.nan
    assert m.pose_error(pred, truth, HEIGHT) == {"mse": 0.0, "rmse_pct": 0.0, "pck_0.05": 1.0, "pck_0.1": 1.0}
    nothing = np.full_like(truth, np.nan)
    assert np.isnan(m.pose_error(nothing, truth, HEIGHT)["mse"])


def test_pck_counts_strictly_closer():
    hits = m.pck_hits(np.array([0.0, 0.05, 0.0499, np.nan]), 0.05)
    np.testing.assert_array_equal(hits[:3], [1.0, 0.0, 1.0])
    assert np.isnan(hits[3])


def test_pose_error_terms_shapes_and_errors():
    squared, distance = m.pose_error_terms(stand(3) + [3.0, 4.0], stand(3), 10.0)
    assert squared.shape == (3, 30) and distance.shape == (3, 15)
    np.testing.assert_allclose(distance, 0.5)
    np.testing.assert_allclose(squared.reshape(3, 15, 2), np.broadcast_to([0.09, 0.16], (3, 15, 2)))
    with pytest.raises(InputError, match="does not match"):
        m.pose_error_terms(stand(3), stand(4), 10.0)
    with pytest.raises(InputError, match="height must be positive"):
        m.pose_error_terms(stand(3), stand(3), 0.0)
    with pytest.raises(InputError, match="height must be positive"):
        m.pose_error_terms(stand(3), stand(3), float("nan"))
