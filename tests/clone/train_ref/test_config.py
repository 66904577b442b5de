"""train_ref.config: the settings stored in the model file read back unchanged."""

from __future__ import annotations

from clone.train_ref import AugmentConfig, LossConfig, TrainConfig


def test_config_round_trips_through_a_plain_dict():
    config = TrainConfig(size=64, depth=3, prev_source="real", augment=AugmentConfig(scale=0.2),
                         loss=LossConfig(l1=50.0))
    data = config.to_dict()
    assert TrainConfig.from_dict(data) == config
    assert isinstance(data["augment"], dict) and data["augment"]["scale"] == 0.2  # left unchanged
    assert TrainConfig.from_dict(TrainConfig().to_dict()) == TrainConfig()
