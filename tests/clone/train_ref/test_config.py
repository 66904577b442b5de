"""train_ref.config: the settings stored in the model file read back unchanged."""

from __future__ import annotations

import pytest

from clone.train_ref import AugmentConfig, LossConfig, TrainConfig
from clone.train_ref.config import PrevSource


def test_config_round_trips_through_a_plain_dict():
    config = TrainConfig(size=64, depth=3, prev_source="real", augment=AugmentConfig(scale=0.2),
                         loss=LossConfig(l1=50.0))
    data = config.to_dict()
    assert TrainConfig.from_dict(data) == config
    assert isinstance(data["augment"], dict) and data["augment"]["scale"] == 0.2  # left unchanged
    assert TrainConfig.from_dict(TrainConfig().to_dict()) == TrainConfig()


def test_prev_source_is_checked_and_stored_as_its_name():
    with pytest.raises(ValueError, match="unknown prev_source 'gen'; valid: generated, real"):
        TrainConfig(prev_source="gen")  # a typo must not switch to teacher forcing
    with pytest.raises(ValueError, match="prev_source"):
        TrainConfig.from_dict({**TrainConfig().to_dict(), "prev_source": "Real"})
    config = TrainConfig(prev_source="real")
    assert config.prev_source is PrevSource.REAL and TrainConfig(prev_source=PrevSource.REAL) == config
    data = config.to_dict()
    assert type(data["prev_source"]) is str and data["prev_source"] == "real"  # plain data in the model file
    assert TrainConfig.from_dict(data).prev_source is PrevSource.REAL
