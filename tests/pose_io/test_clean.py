import numpy as np
import pytest

from pose_io import InputError, PoseTrack, fill_gaps, resample, smooth
from pose_io.resample import resample_values


def line_track(t_len: int = 20, fps: float = 30.0) -> PoseTrack:
    """Every joint moves along x at 2 px/frame; joint j sits at y = 10 j."""
    t = np.arange(t_len, dtype=np.float32)[:, None]
    joints = np.stack(np.broadcast_arrays(10 + 2 * t + np.zeros((1, 15)), 10 * np.arange(15)[None]), axis=-1)
    return PoseTrack(joints, np.full((t_len, 15), 0.8), fps, (200, 200), "body15")


def with_missing(track: PoseTrack, frames, joint: int) -> PoseTrack:
    conf = track.confidence.copy()
    conf[frames, joint] = 0.0
    return track.replace(confidence=conf)


def test_fill_gaps_interpolates_short_gaps_exactly():
    track = line_track()
    holed = with_missing(track, slice(5, 8), 3)
    filled, report = fill_gaps(holed, max_gap=3)
    np.testing.assert_allclose(filled.joints, track.joints, atol=1e-4)
    assert not filled.missing.any()
    assert [(g.joint, g.start, g.stop) for g in report.filled] == [("r_elbow", 5, 8)]
    assert report.frames_filled == 3 and not report.unfilled


def test_fill_gaps_reports_long_and_edge_gaps():
    track = with_missing(with_missing(line_track(), slice(5, 10), 3), slice(0, 2), 4)
    filled, report = fill_gaps(track, max_gap=4)
    assert filled.missing[5:10, 3].all() and filled.missing[0:2, 4].all()
    assert {(g.joint, g.start, g.stop, g.reason) for g in report.unfilled} == {
        ("r_elbow", 5, 10, "too long"), ("r_wrist", 0, 2, "edge")}
    assert "r_elbow frames 5-9 (too long)" in report.summary()
    assert fill_gaps(track, max_gap=0)[1].filled == ()
    with pytest.raises(InputError):
        fill_gaps(track, -1)


def test_smooth_keeps_lines_and_missing():
    track = with_missing(line_track(), [4, 11], 2)
    out = smooth(track, sigma=2.0)
    # Linear motion is a fixed point away from the ends (a symmetric kernel on a line).
    np.testing.assert_allclose(out.joints[8:12, 0], track.joints[8:12, 0], atol=1e-4)
    assert np.array_equal(out.missing, track.missing)
    np.testing.assert_array_equal(out.confidence, track.confidence)
    assert smooth(track, 0.0) is track


def test_smooth_is_confidence_weighted():
    track = line_track()
    joints = track.joints.copy()
    joints[10, 0, 1] += 50.0  # a spike
    spike = track.replace(joints=joints)
    conf = track.confidence.copy()
    conf[10, 0] = 0.01
    faint = track.replace(joints=joints, confidence=conf)
    pull = abs(smooth(spike, 1.5).joints[9, 0, 1] - track.joints[9, 0, 1])
    faint_pull = abs(smooth(faint, 1.5).joints[9, 0, 1] - track.joints[9, 0, 1])
    assert pull > 5.0 and faint_pull < 0.1 * pull


def test_resample_halves_and_interpolates():
    track = line_track(21)
    half = resample(track, 15.0)
    assert half.num_frames == 11 and half.fps == 15.0
    np.testing.assert_array_equal(half.joints, track.joints[::2])
    double = resample(track, 60.0)
    assert double.num_frames == 41
    np.testing.assert_allclose(double.joints[1, :, 0], track.joints[0, :, 0] + 1.0, atol=1e-5)


def test_resample_to_a_frame_count_gives_a_track_its_own_frames_back():
    track = line_track(21)  # 30 fps
    half = resample(track, 15.0)  # 11 frames: frame 20 is frame 10 of the half-rate track
    back = resample(half, 30.0, frames=21)
    assert back.num_frames == 21 and back.fps == 30.0
    np.testing.assert_allclose(back.joints, track.joints, atol=1e-4)  # a line in time survives both ways
    odd = resample(track, 24.0)  # 17 frames, the last at 0.667 s of the track's 0.667 s
    longer = resample(odd, 30.0, frames=23)  # 2 frames past the end hold the last one
    np.testing.assert_array_equal(longer.joints[-3:], np.repeat(odd.joints[-1:], 3, axis=0))
    np.testing.assert_array_equal(resample(track, 15.0, frames=11).joints, half.joints)
    with pytest.raises(InputError, match="at least 1"):
        resample(track, 15.0, frames=0)


def test_resample_values_is_resample_on_gap_free_arrays():
    track = line_track(21)
    for fps, frames in ((15.0, None), (24.0, None), (60.0, None), (30.0, 25)):
        values = resample_values(track.joints.astype(np.float64), 30.0, fps, frames)
        assert values.dtype == np.float64
        np.testing.assert_allclose(values, resample(track, fps, frames).joints, atol=1e-4)
    np.testing.assert_array_equal(resample_values(track.joints, 30.0, 15.0), track.joints[::2])  # frames copied
    with pytest.raises(InputError, match="whole number"):
        resample_values(track.joints, 30.0, 15.0, frames=2.5)
    with pytest.raises(InputError, match="resampling fps"):
        resample_values(track.joints, 0.0, 15.0)


def test_resample_missing_neighbour_makes_missing():
    track = with_missing(line_track(21), [4], 0)
    double = resample(track, 60.0)
    assert double.missing[7:10, 0].tolist() == [True, True, True]  # 3.5, 4, 4.5 all need frame 4
    assert not double.missing[6, 0] and not double.missing[10, 0]
    odd = resample(line_track(10), 24.0)
    assert odd.num_frames == 8  # 9 frame steps at 30 fps = 0.3 s -> 7.2 steps at 24 fps
    with pytest.raises(InputError):
        resample(track, 0.0)


def test_resample_values_on_motion_capture_arrays():
    x = np.arange(13, dtype=np.float64)[:, None, None] * np.ones((1, 17, 3))  # [T, J, 3] like world positions
    np.testing.assert_array_equal(resample_values(x, 120.0, 30.0)[:, 0, 0], [0, 4, 8, 12])  # frames picked exactly
    np.testing.assert_allclose(resample_values(x, 30.0, 60.0)[:3, 0, 0], [0, 0.5, 1.0])
    assert resample_values(x, 30.0, 30.0).shape == x.shape
    assert resample_values(x, 119.88, 30.0).shape[0] == 4  # (13 - 1) * 30 / 119.88 = 3.003: frames 0-3
