"""smooth_joints block by block, into ``out`` or in place, gives scipy's gaussian_filter1d of the whole track,
bit for bit (the filter the authors ran; tests/retarget/network/test_preprocess.py pins short tracks)."""

from __future__ import annotations

import numpy as np
import pytest

from pose_io.clean import smooth_joints


def _scipy(x: np.ndarray, sigma: float) -> np.ndarray:
    from scipy.ndimage import gaussian_filter1d

    return x.copy() if sigma <= 0 else gaussian_filter1d(x, sigma=sigma, axis=0, mode="reflect")


def _track(frames: int, dtype=np.float64) -> np.ndarray:
    return np.random.default_rng(frames).normal(256, 80, (frames, 15, 2)).astype(dtype)  # [T, 15, 2]


@pytest.mark.parametrize("sigma", [0.0, 0.2, 1.0, 2.0, 2.4, 3.7, 40.0, 300.0])
@pytest.mark.parametrize("frames", [1, 5, 60, 1000, 2500])
def test_blocks_out_and_in_place_are_scipy_on_the_whole_track(sigma, frames):
    joints = _track(frames)
    expected = _scipy(joints, sigma)
    for block in (1, 7, 64, 1024, 4096):
        got = smooth_joints(joints, sigma, block=block)
        assert got.dtype == expected.dtype and np.array_equal(got, expected), block
        into = np.full_like(joints, np.nan)
        assert smooth_joints(joints, sigma, out=into, block=block) is into and np.array_equal(into, expected), block
        mine = joints.copy()  # written back a block late, after the next block has read its frames
        assert smooth_joints(mine, sigma, out=mine, block=block) is mine and np.array_equal(mine, expected), block
    assert np.array_equal(joints, _track(frames))  # the input is left alone


@pytest.mark.parametrize("sigma", [0.5, 2.0, 9.0])
def test_float32_and_other_shapes(sigma):
    for frames, shape in ((3000, (15, 2)), (2100, ()), (1500, (3, 4, 2))):
        x = np.random.default_rng(frames).normal(0, 10, (frames, *shape)).astype(np.float32)
        expected = _scipy(x, sigma)
        got = smooth_joints(x, sigma, block=256)
        assert got.dtype == np.float32 and np.array_equal(got, expected)
        mine = x.copy()
        assert np.array_equal(smooth_joints(mine, sigma, out=mine, block=100), expected)


def test_out_of_another_shape_is_refused():
    with pytest.raises(ValueError, match="shape"):
        smooth_joints(_track(10), 2.0, out=np.empty((9, 15, 2)))
