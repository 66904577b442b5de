"""The shipped demo pairs: each isolates its claim, and every ground truth stays inside the frame."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from clone.demo import PAIRS, QUICK, DemoConfig, PairConfig, demo_motions, edge_distance, ground_truth_track
from clone.synth import get_character
from pose_io import PoseTrack


@pytest.mark.parametrize("config", [DemoConfig(), QUICK], ids=["default", "quick"])
def test_every_ground_truth_stays_inside_the_frame(config):
    motions = demo_motions()
    for pair in config.pairs:
        track = ground_truth_track(config, pair, motions)
        assert track.image_size == (config.render_size, config.render_size) and len(track) == pair.frames
        assert edge_distance(track) >= config.edge_margin * config.render_size, pair.name


def test_the_pairs_isolate_proportions_and_view():
    config = DemoConfig()
    assert [p.name for p in PAIRS] == ["proportions", "view", "both"] and config.pairs == PAIRS
    assert (config.render_size, config.model_size) == (256, 256)
    by_name = {p.name: p for p in PAIRS}
    ref_height = get_character(config.reference_character)[0].height

    def other_body(pair: PairConfig) -> bool:
        return abs(get_character(pair.character)[0].height - ref_height) > 0.5

    def yaw_apart(pair: PairConfig) -> float:
        return abs(pair.yaw - config.reference_yaw)

    assert other_body(by_name["proportions"]) and yaw_apart(by_name["proportions"]) == 0
    assert by_name["view"].character == config.reference_character and yaw_apart(by_name["view"]) >= 45
    assert other_body(by_name["both"]) and yaw_apart(by_name["both"]) >= 45
    # Seen from the other side: the camera crosses the front of the body.
    assert np.sign(by_name["view"].yaw) != np.sign(config.reference_yaw)
    motions = demo_motions()
    for pair in PAIRS:
        assert pair.start + pair.frames <= motions[pair.motion].num_frames
    assert all(q.frames < p.frames and q.start == p.start for p, q in zip(PAIRS, QUICK.pairs))


def test_edge_distance_known_values_and_config_checks():
    joints = np.full((2, 15, 2), 30.0)
    joints[0, 0] = [10.0, 20.0]
    joints[0, 1] = [50.0, 59.0]  # 4 px from the bottom edge of a 64² frame (pixel centres 0 .. 63)
    joints[1, 2] = [np.nan, np.nan]  # missing joints do not count
    track = PoseTrack(joints, np.isfinite(joints[..., 0]).astype(float), 30.0, (64, 64), "body15")
    assert edge_distance(track) == 4.0
    assert edge_distance(track.replace(joints=joints - [20.0, 0.0])) == -10.0  # a joint 10 px left of the frame
    with pytest.raises(ValueError, match="distinct names"):
        DemoConfig(pairs=(PAIRS[0], PAIRS[0]))
    with pytest.raises(ValueError, match="distinct names"):
        dataclasses.replace(DemoConfig(), pairs=())
