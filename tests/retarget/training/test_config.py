"""retarget.training.config: TrainConfig round trips, validation and settings added since."""

from __future__ import annotations

import pytest

from retarget.network.model import variant_config
from retarget.training.augment import AugmentConfig
from retarget.training.config import TrainConfig


def test_config_round_trip_and_validation():
    config = TrainConfig(variant="skeleton", augment=AugmentConfig(clip_lengths=(64, 32)))
    assert TrainConfig.from_dict(config.to_dict()) == config
    with pytest.raises(ValueError, match="unknown network variant"):
        TrainConfig(variant="huge")
    with pytest.raises(ValueError, match="window"):
        TrainConfig(window=32)
    assert variant_config(TrainConfig().variant).body_code == 16


def test_config_keeps_its_camera_spread_and_old_configs_get_the_worlds():
    from retarget.world import CameraSpread

    config = TrainConfig(cameras=CameraSpread(max_pitch=25.0, perspective=0.5))
    assert TrainConfig.from_dict(config.to_dict()) == config
    old = TrainConfig().to_dict()
    del old["cameras"]
    assert TrainConfig.from_dict(old).cameras == CameraSpread()
