import logging

import numpy as np
import pytest
import torch

from pose_io import InputError, PoseTrack
from pose_io.clean import hold_fill
from pose_io.layouts import LAYOUTS, JointLayout
from pose_io.readers import read_track
from retarget.inference.placement import Placement, place, placement_of
from retarget.inference.tracks import filled_body15, prepare_track, to_body15, track_scale
from retarget.network.preprocess import (
    LAYOUT,
    NUM_CHANNELS,
    POSE_CHANNELS,
    NormStats,
    PreprocessConfig,
    channels_to_joints,
    joints_to_channels,
    pose_channels,
    row_statistics,
    velocity_channels,
)

CLIPS = ("tall_man", "small_man")


def _stats(seed: int = 0) -> NormStats:
    rng = np.random.default_rng(seed)
    return NormStats(rng.normal(0, 20, (15, 2)), rng.uniform(5, 30, (15, 2)))


def _random_joints(b: int = 2, t: int = 24, seed: int = 0) -> torch.Tensor:
    rng = np.random.default_rng(seed)
    return torch.from_numpy(rng.uniform(50, 450, (b, t, 15, 2)))


def test_channels_round_trip_with_start():
    joints = _random_joints()
    stats = _stats()
    x = joints_to_channels(joints, stats)
    assert x.shape == (2, NUM_CHANNELS, 24)
    back = channels_to_joints(x, stats, start=joints[:, 0, LAYOUT.index("mid_hip")] * 0)
    # The root trajectory restarts from `start` + v[0] = the origin, so compare root-relative poses and travel.
    root = LAYOUT.index("mid_hip")
    torch.testing.assert_close(back - back[:, :1, root : root + 1], joints - joints[:, :1, root : root + 1])


def test_channel_layout_matches_the_authors_convention():
    joints = _random_joints(1, 3)
    x = joints_to_channels(joints, NormStats(np.zeros((15, 2)), np.ones((15, 2))))
    root = joints[0, :, LAYOUT.index("mid_hip")]
    # Row 0 = nose - root, row 8 = r_hip - root (mid_hip skipped), row 14 = root velocity with v[0] = 0.
    torch.testing.assert_close(x[0, 0:2].T, joints[0, :, LAYOUT.index("nose")] - root)
    torch.testing.assert_close(x[0, 16:18].T, joints[0, :, LAYOUT.index("r_hip")] - root)
    torch.testing.assert_close(x[0, 28:30, 0], torch.zeros(2, dtype=x.dtype))
    torch.testing.assert_close(x[0, 28:30, 2], root[2] - root[1])
    assert pose_channels(x).shape[1] == POSE_CHANNELS and velocity_channels(x).shape[1] == 2


def test_row_statistics_normalise_to_zero_mean_unit_std():
    joints = _random_joints(4, 32, seed=3).numpy()
    stats = row_statistics(joints)
    x = joints_to_channels(torch.from_numpy(joints), stats)
    assert abs(float(x.mean())) < 1e-6
    np.testing.assert_allclose(x.transpose(1, 2).reshape(-1, 30).std(dim=0, unbiased=False).numpy(), 1.0, atol=1e-6)


def test_row_statistics_floor_the_std():
    joints = np.zeros((2, 8, 15, 2))
    assert (row_statistics(joints).std == 1.0).all()


def test_stats_reject_bad_shapes_and_zero_std():
    with pytest.raises(InputError, match="must be"):
        NormStats(np.zeros((14, 2)), np.ones((14, 2)))
    with pytest.raises(InputError, match="non-positive"):
        NormStats(np.zeros((15, 2)), np.zeros((15, 2)))


def test_hold_fill_forward_then_backward():
    joints = np.arange(5 * 2 * 2, dtype=np.float64).reshape(5, 2, 2)
    joints[0:2, 0] = np.nan  # leading gap: from frame 2
    joints[3, 1] = np.nan  # inner gap: from frame 2
    filled = hold_fill(joints)
    np.testing.assert_array_equal(filled[0, 0], joints[2, 0])
    np.testing.assert_array_equal(filled[1, 0], joints[2, 0])
    np.testing.assert_array_equal(filled[3, 1], joints[2, 1])
    assert not np.isnan(filled).any()


def test_placement_and_place():
    rng = np.random.default_rng(0)
    joints = rng.uniform(100, 300, (20, 15, 2))
    target = Placement(height=1.0, root_x=40.0, ground_y=500.0)
    moved = placement_of(place(joints, target))
    assert moved.root_x == pytest.approx(40.0) and moved.ground_y == pytest.approx(500.0)


def test_prepare_track_errors(walking_track):
    cfg = PreprocessConfig()
    empty = walking_track.replace(confidence=np.zeros_like(walking_track.confidence))
    with pytest.raises(InputError, match="no joints detected"):
        prepare_track(empty, cfg)
    conf = walking_track.confidence.copy()
    conf[:, walking_track.joint_layout.index("l_wrist")] = 0
    with pytest.raises(InputError, match="never detected.*l_wrist"):
        prepare_track(walking_track.replace(confidence=conf), cfg, "driver.json")
    coco17 = PoseTrack(np.zeros((3, 17, 2)), np.ones((3, 17)), 30, (64, 64), "coco17")
    assert prepare_track(coco17, cfg).shape == (3, 15, 2)  # neck and mid_hip are derived


def test_prepare_track_rejects_a_layout_without_body15_joints(monkeypatch):
    # Every shipped layout gives body15; register one that cannot.
    tiny = JointLayout("tiny2", ("nose", "neck"), (("neck", "nose"),), ((1, 2, 3), (4, 5, 6)))
    monkeypatch.setitem(LAYOUTS, "tiny2", tiny)
    track = PoseTrack(np.ones((3, 2, 2)), np.ones((3, 2)), 30, (64, 64), "tiny2")
    with pytest.raises(InputError, match="ref.json: layout tiny2 cannot give body15 joints"):
        prepare_track(track, PreprocessConfig(), "ref.json")


def test_outlier_joint_never_reaches_the_network(walking_track, caplog):
    """A wrist far outside the image and the body (a track made in code) is dropped, with one warning."""
    wrist = walking_track.joint_layout.index("r_wrist")
    joints = walking_track.joints.copy()
    joints[5, wrist] = (9000.0, 100.0)  # 13 image widths out: the constructor allows it, the body rule does not
    track = walking_track.replace(joints=joints)
    with caplog.at_level(logging.WARNING, logger="retarget.inference.tracks"):
        body = to_body15(track, "driver.npz")
    records = [r.getMessage() for r in caplog.records if r.name == "retarget.inference.tracks"]
    assert len(records) == 1 and records[0].startswith("driver.npz: dropped 1 outlier joint")
    assert body.missing[5, LAYOUT.index("r_wrist")] and body.missing.sum() == 1
    filled = filled_body15(track)
    assert filled[..., 0].max() < 640  # held from frame 4 instead
    cfg = PreprocessConfig(body_height=300.0)
    assert track_scale(track, cfg) == pytest.approx(track_scale(walking_track, cfg))
    np.testing.assert_allclose(prepare_track(track, PreprocessConfig())[:5],
                               prepare_track(walking_track, PreprocessConfig())[:5], atol=20)


def test_a_body_too_small_to_measure_cannot_be_scaled(walking_track):
    tiny = walking_track.replace(joints=walking_track.joints * 1e-4)
    with pytest.raises(InputError, match="tiny.npz: skeleton height: .* at least 1 pixel tall"):
        track_scale(tiny, PreprocessConfig(body_height=300.0), "tiny.npz")


@pytest.mark.parametrize("clip", CLIPS)
def test_parity_preprocessing(shared_dir, clip):
    parity = shared_dir / "official_2dmr" / "parity"
    weights = shared_dir / "official_2dmr" / "weights"
    track = read_track(shared_dir / "openpose_examples" / clip, image_size=(720, 720)).frames(0, 120)
    unsmoothed = hold_fill(track.to_layout("body15").joints.astype(np.float64))
    np.testing.assert_allclose(unsmoothed.transpose(1, 2, 0), np.load(parity / f"raw_unsmoothed_{clip}.npy"), atol=1e-3)
    raw = prepare_track(track, PreprocessConfig())
    np.testing.assert_allclose(raw.transpose(1, 2, 0), np.load(parity / f"raw_{clip}.npy"), atol=1e-3)
    stats = NormStats(np.load(weights / "meanpose_with_view.npy"), np.load(weights / "stdpose_with_view.npy"))
    x = joints_to_channels(torch.from_numpy(raw)[None], stats).numpy()
    np.testing.assert_allclose(x, np.load(parity / f"full_norm_{clip}.npy"), atol=1e-4)


# ---------------------------------------------------------------------------------------------------------
# The numpy inference path shares these functions: arrays give exactly what tensors give.


def test_channel_functions_take_arrays_and_give_what_tensors_give():
    stats = _stats(3)
    joints = _random_joints(b=3, t=40, seed=3).double()
    x_torch = joints_to_channels(joints, stats)
    x_numpy = joints_to_channels(joints.numpy(), stats)
    assert isinstance(x_numpy, np.ndarray) and x_numpy.dtype == np.float64
    np.testing.assert_array_equal(x_numpy, x_torch.numpy())
    start = np.array([[10.0, 20.0], [0.0, 1.0], [5.0, 5.0]])
    back_torch = channels_to_joints(x_torch, stats, torch.from_numpy(start))
    back_numpy = channels_to_joints(x_numpy, stats, start)
    np.testing.assert_array_equal(back_numpy, back_torch.numpy())
    np.testing.assert_array_equal(pose_channels(x_numpy), x_numpy[:, :POSE_CHANNELS])
    np.testing.assert_array_equal(velocity_channels(x_numpy), x_numpy[:, POSE_CHANNELS:])
    assert joints_to_channels(joints.numpy().astype(np.float32), stats).dtype == np.float32


def test_smoothing_is_scipys_gaussian_filter_to_the_bit():
    """pose_io.clean.smooth_joints (numpy, so that short runs need not import scipy) = scipy's gaussian_filter1d."""
    from scipy.ndimage import gaussian_filter1d

    from pose_io.clean import smooth_joints

    rng = np.random.default_rng(0)
    for trial in range(300):
        frames = int(rng.integers(1, 70))  # shorter than the kernel too (repeated reflection)
        shape = (frames, *rng.integers(1, 5, size=int(rng.integers(0, 3))))
        dtype = np.float32 if trial % 3 == 0 else np.float64
        x = (rng.normal(size=shape) * 10 ** rng.uniform(-3, 4)).astype(dtype)
        sigma = float(rng.choice([0.2, 0.5, 1.0, 2.0, 3.3, 7.0]))
        expected = gaussian_filter1d(x, sigma=sigma, axis=0, mode="reflect")
        got = smooth_joints(x, sigma)
        assert got.dtype == expected.dtype
        np.testing.assert_array_equal(got, expected, err_msg=f"{shape} {dtype} sigma={sigma}")
