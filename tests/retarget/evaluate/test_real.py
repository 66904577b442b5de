"""Real-track pairs: what is measured without ground truth, on small synthetic tracks."""

from __future__ import annotations

import numpy as np
import pytest

from pose_io.clean import smooth_joints
from pose_io.measures import skeleton_height
from pose_io.track import PoseTrack
from retarget.baselines.methods import global_scale_retarget
from retarget.evaluate.real import markdown_rows, pair_scores, real_pair_results, wrist_rise
from retarget.inference.tracks import body15_track, filled_body15
from retarget.network.preprocess import LAYOUT, ROOT


def _smaller(track: PoseTrack) -> PoseTrack:
    """The same person 0.8 times as tall, standing elsewhere in the frame."""
    return track.replace(joints=track.joints * np.float32(0.8) + np.float32([60.0, 80.0]))


def _own_track(motion: PoseTrack, reference: PoseTrack) -> PoseTrack:
    """A fake method that ignores the motion and returns the reference's own (body15) track."""
    return body15_track(filled_body15(reference), reference.fps, reference.image_size)


def test_wrist_rise_known_value() -> None:
    joints = np.zeros((3, 15, 2))
    joints[:, LAYOUT.index("neck"), 1] = 100.0
    joints[:, LAYOUT.index("r_wrist"), 1] = [120.0, 90.0, 110.0]  # 10 px above the neck in frame 1
    joints[:, LAYOUT.index("l_wrist"), 1] = [130.0, 125.0, np.nan]  # a missing wrist does not count
    assert wrist_rise(joints, 50.0) == pytest.approx(20.0)
    joints[:, LAYOUT.index("r_wrist"), 1] = 104.0  # never above the neck: a negative rise
    assert wrist_rise(joints, 50.0) == pytest.approx(-8.0)


@pytest.mark.parametrize("sigma", [0.0, 2.0])
def test_driver_scaled_to_another_height_keeps_the_whole_motion(walking_track: PoseTrack, sigma: float) -> None:
    # The output is the (as measured, smoothed) driver 1.5 times as tall and moved: nothing damped or raised.
    driver = smooth_joints(filled_body15(walking_track), sigma)
    output = body15_track(driver * 1.5 + [10.0, -30.0], walking_track.fps, walking_track.image_size)
    scores = pair_scores(walking_track, _smaller(walking_track), output, sigma=sigma)
    assert scores["amplitude"] == pytest.approx(1.0, rel=1e-5)
    assert ROOT not in scores["amplitude_per_joint"]
    assert set(scores["amplitude_per_joint"]) == set(LAYOUT.joints) - {ROOT}
    assert all(r == pytest.approx(1.0, abs=1e-4) for r in scores["amplitude_per_joint"].values())
    assert scores["wrist_rise_pct"] == pytest.approx(scores["driver_wrist_rise_pct"], abs=1e-4)
    # 1.5 times the driver is not the reference's 0.8: every limb is 0.7 / 0.8 of its own length off.
    assert scores["proportion_error_pct"] > 5.0


def test_the_reference_own_track_has_its_limbs(walking_track: PoseTrack) -> None:
    reference = _smaller(walking_track)
    scores = pair_scores(walking_track, reference, _own_track(walking_track, reference))
    assert scores["proportion_error_pct"] == pytest.approx(0.0, abs=1e-6)
    own = filled_body15(reference)  # the output is the reference: its wrists rise as the reference's do
    assert scores["wrist_rise_pct"] == pytest.approx(wrist_rise(own, skeleton_height(own, LAYOUT)), rel=1e-5)


def test_every_ordered_pair_by_every_method(walking_track: PoseTrack) -> None:
    tracks = {"tall": walking_track, "small": _smaller(walking_track)}
    methods = {"global scaling (EDN)": global_scale_retarget, "own track": _own_track}
    results = real_pair_results(tracks, methods)
    assert list(results) == ["tall -> small", "small -> tall"]
    for rows in results.values():
        assert list(rows) == list(methods)
        # Two sizes of one person: global scaling gives B's proportions and moves like B's own track.
        edn, own = rows["global scaling (EDN)"], rows["own track"]
        assert edn["proportion_error_pct"] == pytest.approx(0.0, abs=1e-3)
        assert edn["amplitude"] == pytest.approx(own["amplitude"], rel=1e-4)
        assert np.isfinite(edn["wrist_rise_pct"]) and np.isfinite(edn["driver_wrist_rise_pct"])
    lines = markdown_rows(results)
    assert len(lines) == 2 + 4
    assert lines[2].startswith("| tall -> small | global scaling (EDN) | ")
