import numpy as np
import pytest

from pose_io import BODY15, InputError
from pose_io.clean import interpolate_missing
from pose_io.measures import foot_points
from retarget.baselines.global_scale import (
    ScaleStats,
    apply_global_scale,
    global_scale_params,
    scale_stats,
)


def walking_body15(frames: int = 60, seed: int = 0) -> np.ndarray:
    """[T, 15, 2] a figure that walks towards the camera: lower and larger over time."""
    rng = np.random.default_rng(seed)
    base = np.array(
        [[0, -170], [0, -150], [-25, -150], [-30, -110], [-32, -75], [25, -150], [30, -110], [32, -75],
         [0, -80], [-12, -80], [-13, -40], [-14, 0], [12, -80], [13, -40], [14, 0]], dtype=np.float64)
    t = np.arange(frames)[:, None]
    s = (0.6 + 0.4 * t / frames)[..., None]  # apparent size grows as the feet come down the image
    joints = base[None] * s
    joints[:, BODY15.index("l_ankle"), 1] -= 6 * np.abs(np.sin(t[:, 0] / 3.0))  # one foot lifts
    joints[..., 0] += 300 + 40 * np.sin(t / 10.0)
    joints[..., 1] += 250 + 150 * t / frames
    return (joints + rng.normal(0, 0.3, joints.shape)).astype(np.float32)


def test_driver_equal_to_reference_maps_to_itself():
    ref = walking_body15()
    stats = scale_stats(ref, BODY15)
    out = apply_global_scale(ref, BODY15, stats, stats)
    np.testing.assert_allclose(out, ref, atol=1e-3)


def test_driver_scaled_by_two_comes_back_at_reference_scale():
    ref = walking_body15()
    driver = ref * 2.0 + np.array([13.0, -40.0], dtype=np.float32)
    out = apply_global_scale(driver, BODY15, scale_stats(driver, BODY15), scale_stats(ref, BODY15))
    np.testing.assert_allclose(out, ref, atol=1e-2)


def test_known_parameters():
    source = ScaleStats(foot_far=100, foot_close=300, height_far=50, height_close=100, center_x=0, foot_median=200)
    target = ScaleStats(foot_far=200, foot_close=400, height_far=100, height_close=150, center_x=10, foot_median=390)
    scale, y = global_scale_params(np.array([100.0, 200.0, 300.0]), source, target)
    np.testing.assert_allclose(scale, [2.0, 1.75, 1.5])
    np.testing.assert_allclose(y, [200.0, 300.0, 400.0])


def test_driver_standing_in_place_keeps_one_depth():
    # Feet range 2 px for a 100 px tall driver: its jitter must not be stretched over the target's 200 px.
    flat = ScaleStats(foot_far=99, foot_close=101, height_far=100, height_close=100, center_x=0, foot_median=100)
    target = ScaleStats(foot_far=200, foot_close=400, height_far=100, height_close=300, center_x=10, foot_median=390)
    scale, y = global_scale_params(np.array([99.0, 100.0, 101.0]), flat, target)
    np.testing.assert_allclose(scale, [2.0, 2.0, 2.0])
    np.testing.assert_allclose(y, [388.0, 390.0, 392.0])
    # With the guard off, the paper's formula maps the 2 px onto the whole range.
    _, y = global_scale_params(np.array([99.0, 101.0]), flat, target, min_span=0.0)
    np.testing.assert_allclose(y, [200.0, 400.0])


def test_foot_is_the_lower_ankle_and_missing_frames_are_interpolated():
    j = walking_body15(10)
    feet = foot_points(j, BODY15)
    lower = np.maximum(j[:, BODY15.index("l_ankle"), 1], j[:, BODY15.index("r_ankle"), 1])
    np.testing.assert_allclose(feet[:, 1], lower)
    j[4, BODY15.indices(("l_ankle", "r_ankle"))] = np.nan
    assert np.isnan(foot_points(j, BODY15)[4]).all()
    np.testing.assert_allclose(interpolate_missing(np.array([1.0, np.nan, 3.0, np.nan])), [1, 2, 3, 3])
    stats = scale_stats(j, BODY15)
    out = apply_global_scale(j, BODY15, stats, stats)
    assert np.isfinite(out[4, BODY15.index("neck")]).all()
    assert np.isnan(out[4, BODY15.index("l_ankle")]).all()


def test_no_ankles_is_a_clear_error():
    j = walking_body15(5)
    j[:, BODY15.indices(("l_ankle", "r_ankle"))] = np.nan
    with pytest.raises(InputError, match="ankles"):
        scale_stats(j, BODY15)


def test_stats_dict_round_trip():
    stats = scale_stats(walking_body15(), BODY15)
    assert ScaleStats.from_dict(stats.to_dict()) == stats
    assert stats.foot_close > stats.foot_far and stats.height_close > stats.height_far
