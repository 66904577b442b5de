"""train_ref.config: the settings stored in the model file read back unchanged."""

from __future__ import annotations

import pytest

from clone.model.background import PlateConfig
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


def test_background_settings_round_trip_and_older_runs_had_none():
    config = TrainConfig(plate_input=True, plate=PlateConfig(max_frames=20, margin=0.3))
    assert TrainConfig.from_dict(config.to_dict()) == config
    g = config.generator_config()
    assert g.alpha and g.plate_input and g.in_channels == 9 and g.exemplar  # pose, previous frame, exemplar
    assert TrainConfig(size=64).generator_config().in_channels == 6  # no exemplar below 128²
    assert not TrainConfig(background=False, plate_input=True).generator_config().uses_plate
    old = {k: v for k, v in TrainConfig().to_dict().items() if k not in ("background", "plate_input", "plate")}
    assert TrainConfig.from_dict(old) == TrainConfig(background=False)


def test_the_learning_rate_falls_linearly_over_the_runs_last_part():
    constant, tail = TrainConfig(lr_decay_from=1.0), TrainConfig(lr_decay_from=0.5)
    assert TrainConfig().lr_decay_from == 0.5  # the default, chosen on real footage
    assert [constant.lr_factor(p) for p in (0.0, 0.7, 1.0)] == [1.0, 1.0, 1.0]
    assert [tail.lr_factor(p) for p in (0.0, 0.5, 0.75, 1.0)] == [1.0, 1.0, 0.5, 0.0]
    assert TrainConfig(lr_decay_from=0.0).lr_factor(0.25) == 0.75
    with pytest.raises(ValueError, match="lr_decay_from"):
        TrainConfig(lr_decay_from=1.5)
    stored = TrainConfig().to_dict()
    del stored["lr_decay_from"]  # a model trained before the schedule resumes with a constant rate
    assert TrainConfig.from_dict(stored).lr_decay_from == 1.0


def test_the_face_pass_is_on_from_128_up_with_detailed_maps_and_older_runs_had_none():
    assert TrainConfig(size=256).face_pass and TrainConfig(size=128).face_pass and not TrainConfig(size=64).face_pass
    assert TrainConfig(size=64, face_pass=True).face_pass
    assert not TrainConfig(size=256, pose_layout="body15").face_pass
    assert not TrainConfig(size=256, face_pass=False).face_pass
    stored = TrainConfig(size=256).to_dict()
    assert TrainConfig.from_dict(stored).face_pass
    del stored["face_pass"]
    assert not TrainConfig.from_dict(stored).face_pass
