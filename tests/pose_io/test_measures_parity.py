"""Fast paths of pose_io.measures give the general formulas' numbers bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from pose_io.measures import segment_lengths, skeleton_heights


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("frames", [50, 3000])  # through transposed planes / segment by segment (long)
def test_segment_lengths_are_linalg_norm_to_the_bit(seed, frames):
    rng = np.random.default_rng(seed)
    joints = rng.normal(0, 10.0 ** rng.uniform(-3, 4), (3, frames, 15, 2))
    joints[rng.random(joints.shape[:-1]) < 0.1] = np.nan
    pairs = rng.integers(0, 15, (9, 2))
    expected = np.linalg.norm(joints[..., pairs[:, 0], :] - joints[..., pairs[:, 1], :], axis=-1)
    assert segment_lengths(joints, pairs).tobytes() == expected.tobytes()


@pytest.mark.filterwarnings("ignore:All-NaN slice")  # the reference on one frame without a nose
@pytest.mark.parametrize("frames", [1, 2, 7, 120, 599, 600, 601, 2000])
def test_skeleton_heights_without_gaps_are_the_nanmedian_ones(frames):
    rng = np.random.default_rng(frames)
    joints = rng.normal(200, 60, (2, frames, 15, 2))
    joints[1, :: max(2, frames // 3), 4] = np.nan  # a wrist (no bone of the height) missing: still no gap
    joints[1, ::3, 0] = np.nan  # the nose missing in some frames: a gap, nanmedian
    lengths = segment_lengths(joints, np.array([[0, 1], [1, 8], [12, 13], [13, 14], [9, 10], [10, 11]]))
    bones = np.nanmedian(lengths, axis=1)  # [2, 6]
    expected = bones[:, 0] + bones[:, 1] + 0.5 * bones[:, 2:].sum(axis=1)
    assert skeleton_heights(joints, "body15").tobytes() == expected.tobytes()


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_foot_points_pick_the_lower_ankle_as_the_argmax_did(dtype):
    from pose_io.layouts import BODY15
    from pose_io.measures import ANKLES, foot_points

    rng = np.random.default_rng(7)
    joints = rng.integers(0, 5, (400, 15, 2)).astype(dtype)  # small integers: many ties
    joints[rng.random((400, 15)) < 0.3] = np.nan
    ankles = joints[:, BODY15.indices(ANKLES)]  # the argmax formulation it replaced
    y = np.where(np.isnan(ankles[..., 1]), -np.inf, ankles[..., 1])
    expected = ankles[np.arange(len(joints)), np.argmax(y, axis=1)].astype(np.float64)
    expected[~np.isfinite(y).any(axis=1)] = np.nan
    got = foot_points(joints, BODY15)
    assert got.dtype == np.float64 and got.tobytes() == expected.tobytes()


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("n", [1, 2, 3, 4, 119, 120, 10_000])
def test_median_of_is_np_median_to_the_bit(n, dtype):
    from pose_io.measures import median_of

    rng = np.random.default_rng(n)
    values = rng.normal(0, 100, (n, 6)).astype(dtype)
    values[rng.random(values.shape) < 0.2] = 0.5  # ties
    values[0, 0] = -0.0
    for got, expected in [
        (median_of(values), np.median(values, axis=0)),
        (median_of(values, axis=1), np.median(values, axis=1)),
        (median_of(values[:, 3]), np.median(values[:, 3])),
        (median_of(values.T, axis=-1), np.median(values.T, axis=-1)),
    ]:
        assert np.asarray(got).dtype == np.asarray(expected).dtype
        assert np.asarray(got).tobytes() == np.asarray(expected).tobytes()
