"""retarget.training.loop: fit, its checkpoints, resume, the best epoch, the weight average, progress."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import torch

from pose_io import InputError, PoseTrack
from retarget.api import load_retargeter
from retarget.network.checkpoint import load_checkpoint
from retarget.training.config import TrainConfig
from retarget.training.data import mean_pose_height
from retarget.training.loop import fit, retargeting_error
from tests.retarget.training.fake_split import TINY, FakeSplit, weights_of


def test_fit_writes_a_checkpoint_the_retargeter_loads(tmp_path, walking_track):
    split = FakeSplit()
    summary = fit(split, FakeSplit(seed=1), tmp_path / "r.pt", TINY, epochs=2)
    assert summary.epochs == 2 and summary.steps == 4 and summary.stopped == "epochs"
    assert {"train_rec", "train_cross", "train_foot", "train_triplet", "val_total"} <= set(summary.history[-1])
    loaded = load_checkpoint(tmp_path / "r.pt")
    assert loaded.training["epoch"] == 2 and loaded.variant == "full"
    retargeter = load_retargeter(tmp_path / "r.pt")
    out = retargeter.retarget(walking_track, retargeter.reference_codes(walking_track))
    assert len(out) == len(walking_track)


def test_resume_continues_exactly(tmp_path):
    split, val = FakeSplit(), FakeSplit(seed=1)
    fit(split, val, tmp_path / "whole.pt", TINY, epochs=2)
    # Stop after the first step (a zero budget), then resume to the end.
    first = fit(split, val, tmp_path / "parts.pt", TINY, epochs=2, minutes=0.0)
    assert first.stopped == "time" and first.steps == 1
    rest = fit(split, val, tmp_path / "parts.pt", TINY, epochs=2, resume=True)
    assert rest.epochs == 2 and rest.steps == 4
    whole, parts = weights_of(tmp_path / "whole.pt"), weights_of(tmp_path / "parts.pt")
    for key in whole:
        torch.testing.assert_close(parts[key], whole[key], rtol=0, atol=0)


def test_best_keeps_the_weights_of_the_epoch_with_the_lowest_validation_error(tmp_path):
    split, val = FakeSplit(), FakeSplit(seed=1)
    config = dataclasses.replace(TINY, loss=dataclasses.replace(TINY.loss, trajectory_weight=0.5))
    summary = fit(split, val, tmp_path / "r.pt", config, epochs=5, best=tmp_path / "best.pt")
    errors = [retargeting_error(r, config) for r in summary.history]
    assert summary.best_epoch == int(np.argmin(errors)) + 1
    best = load_checkpoint(tmp_path / "best.pt")
    assert best.training is None  # weights only
    fit(split, val, tmp_path / "short.pt", config, epochs=summary.best_epoch)  # the same run, stopped there
    same = weights_of(tmp_path / "short.pt")
    for key, value in best.model.state_dict().items():
        torch.testing.assert_close(value, same[key], rtol=0, atol=0)
    # Resumed, an epoch is kept only when it beats every earlier one of the run.
    fit(split, val, tmp_path / "parts.pt", config, epochs=2, best=tmp_path / "b2.pt")
    rest = fit(split, val, tmp_path / "parts.pt", config, epochs=5, resume=True, best=tmp_path / "b2.pt")
    assert [retargeting_error(r, config) for r in rest.history] == errors
    assert rest.best_epoch == (summary.best_epoch if summary.best_epoch > 2 else None)
    kept = load_checkpoint(tmp_path / "b2.pt").model.state_dict()
    for key, value in best.model.state_dict().items():
        torch.testing.assert_close(kept[key], value, rtol=0, atol=0)
    # No validation split: nothing to choose by.
    alone = fit(split, None, tmp_path / "alone.pt", config, epochs=1, best=tmp_path / "b3.pt")
    assert alone.best_epoch is None and not (tmp_path / "b3.pt").exists()


def test_average_is_the_mean_of_the_weights_of_the_chosen_epochs_across_resumes(tmp_path):
    split, val = FakeSplit(), FakeSplit(seed=1)
    whole = fit(split, val, tmp_path / "whole.pt", TINY, epochs=4, average=tmp_path / "mean.pt", average_from=2)
    assert whole.averaged_epochs == 3
    ends = []
    for epochs in (1, 2, 3, 4):  # the same run, one epoch per call
        fit(split, val, tmp_path / "parts.pt", TINY, epochs=epochs, resume=epochs > 1,
            average=tmp_path / "parts_mean.pt", average_from=2)
        ends.append(weights_of(tmp_path / "parts.pt"))
    mean, parts_mean = weights_of(tmp_path / "mean.pt"), weights_of(tmp_path / "parts_mean.pt")
    for key, value in mean.items():
        expected = sum(end[key].double() for end in ends[1:]) / 3
        torch.testing.assert_close(value.double(), expected, rtol=0, atol=1e-6)
        torch.testing.assert_close(parts_mean[key], value, rtol=0, atol=0)
    assert not torch.equal(mean["motion_encoder.layers.0.weight"], ends[-1]["motion_encoder.layers.0.weight"])
    assert load_checkpoint(tmp_path / "mean.pt").training is None
    # A call without the option in between: its epoch still joins the mean.
    fit(split, val, tmp_path / "gap.pt", TINY, epochs=2, average=tmp_path / "gap_mean.pt", average_from=2)
    fit(split, val, tmp_path / "gap.pt", TINY, epochs=3, resume=True)
    last = fit(split, val, tmp_path / "gap.pt", TINY, epochs=4, resume=True, average=tmp_path / "gap_mean.pt")
    assert last.averaged_epochs == 1  # added by this call
    for key, value in weights_of(tmp_path / "gap_mean.pt").items():
        torch.testing.assert_close(value, mean[key], rtol=0, atol=0)
    for option in ("best", "average"):
        with pytest.raises(InputError, match="would replace the checkpoint"):
            fit(split, val, tmp_path / "whole.pt", TINY, epochs=5, resume=True, **{option: tmp_path / "whole.pt"})
    # A run that went past the first averaged epoch without averaging cannot start now.
    fit(split, val, tmp_path / "plain.pt", TINY, epochs=2)
    with pytest.raises(InputError, match="start it later"):
        fit(split, val, tmp_path / "plain.pt", TINY, epochs=5, resume=True, average=tmp_path / "m2.pt", average_from=2)
    fit(split, val, tmp_path / "plain.pt", TINY, epochs=3, resume=True, average=tmp_path / "m2.pt", average_from=3)
    torch.testing.assert_close(weights_of(tmp_path / "m2.pt"), weights_of(tmp_path / "plain.pt"), rtol=0, atol=0)
    with pytest.raises(InputError, match="from epoch 2; resume with that"):
        fit(split, val, tmp_path / "parts.pt", TINY, epochs=5, resume=True, average=tmp_path / "m2.pt",
            average_from=3)


def test_retargeting_error_is_cross_reconstruction_plus_the_unweighted_root_path():
    record = {"val_rec": 0.2, "val_cross": 0.5, "val_trajectory": 0.03}
    with_path = dataclasses.replace(TINY, loss=dataclasses.replace(TINY.loss, trajectory_weight=0.1))
    assert retargeting_error(record, with_path) == pytest.approx(0.8)
    assert retargeting_error(record, TINY) == pytest.approx(0.5)  # the root path is not trained
    no_cross = dataclasses.replace(TINY, loss=dataclasses.replace(TINY.loss, cross=False))
    assert retargeting_error(record, no_cross) == pytest.approx(0.2)
    assert retargeting_error({"train_cross": 0.5}, TINY) is None


def test_fit_refuses_to_overwrite_or_to_resume_other_settings(tmp_path):
    split = FakeSplit()
    fit(split, None, tmp_path / "r.pt", TINY, epochs=1)
    with pytest.raises(InputError, match="already exists; pass --resume"):
        fit(split, None, tmp_path / "r.pt", TINY, epochs=1)
    with pytest.raises(InputError, match="other settings.*batch_size"):
        fit(split, None, tmp_path / "r.pt", TrainConfig(batch_size=2, samples_per_epoch=8, stats_windows=32),
            epochs=2, resume=True)
    with pytest.raises(InputError, match="nothing to resume"):
        fit(split, None, tmp_path / "none.pt", TINY, epochs=1, resume=True)


def test_resume_fills_settings_added_since_with_their_defaults(tmp_path):
    split = FakeSplit()
    fit(split, None, tmp_path / "r.pt", TINY, epochs=1)
    state = torch.load(tmp_path / "r.pt", weights_only=False)
    del state["training"]["config"]["extra_characters"]  # as written before the setting existed
    torch.save(state, tmp_path / "r.pt")
    assert fit(split, None, tmp_path / "r.pt", TINY, epochs=2, resume=True).epochs == 2
    other = dataclasses.replace(TINY, extra_spread=2.0)
    with pytest.raises(InputError, match="other settings.*extra_spread"):
        fit(split, None, tmp_path / "r.pt", other, epochs=3, resume=True)


def test_real_tracks_join_with_self_reconstruction(tmp_path, walking_track):
    t = np.arange(80)[:, None]
    joints = np.concatenate([walking_track.joints, walking_track.joints[::-1]])  # 80 frames
    joints = joints + np.stack([2 * np.sin(t / 7.0), np.zeros_like(t)], -1)[:, :, 0][:, None]
    real = PoseTrack(joints, np.full(joints.shape[:2], 0.9), 30, (640, 480), "body25")
    summary = fit(FakeSplit(), None, tmp_path / "r.pt", TINY, real_tracks=[real], epochs=1)
    assert summary.history[-1]["train_real"] > 0


@pytest.mark.parametrize("variant", ["skeleton", "view"])
def test_two_encoder_variants_train(tmp_path, variant):
    config = TrainConfig(variant=variant, batch_size=2, samples_per_epoch=2, val_samples=2, stats_windows=16)
    summary = fit(FakeSplit(), FakeSplit(seed=1), tmp_path / "r.pt", config, epochs=1)
    assert load_checkpoint(summary.checkpoint).variant == variant


def test_fit_starts_from_given_weights_and_keeps_their_statistics(tmp_path):
    split = FakeSplit()
    fit(split, None, tmp_path / "first.pt", TINY, epochs=1)
    start = load_checkpoint(tmp_path / "first.pt")
    fit(split, None, tmp_path / "tuned.pt", TINY, epochs=1, init=start)
    tuned = load_checkpoint(tmp_path / "tuned.pt")
    np.testing.assert_array_equal(tuned.stats.mean, start.stats.mean)
    assert tuned.training["init"] == str(tmp_path / "first.pt")
    assert tuned.preprocess.body_height == pytest.approx(mean_pose_height(start.stats), abs=1e-3)
    assert any(not torch.equal(a, b) for a, b in zip(tuned.model.state_dict().values(),
                                                      start.model.state_dict().values()))  # fmt: skip
    with pytest.raises(InputError, match="a full network; this run trains a skeleton one"):
        fit(split, None, tmp_path / "other.pt", TrainConfig(variant="skeleton"), epochs=1, init=start)


def test_progress_is_a_callback_of_every_step_and_epoch(tmp_path):
    seen = []
    fit(FakeSplit(), FakeSplit(seed=1), tmp_path / "r.pt", TINY, epochs=2, progress=seen.append)
    steps = [p for p in seen if "epoch" not in p.losses]
    ends = [p for p in seen if "epoch" in p.losses]
    assert [p.global_step for p in steps] == [1, 2, 3, 4]
    assert [(p.epoch, p.step, p.steps_per_epoch) for p in ends] == [(1, 2, 2), (2, 2, 2)]
    assert "val_total" in ends[-1].losses and "total" in steps[0].losses


def test_fit_feeds_the_training_characters_proportions_to_the_skeleton_proportion_term(tmp_path, monkeypatch):
    from retarget.training import state

    seen = []

    def table(split):  # the fake split's characters are not Skeletons; any [C, P] table will do
        seen.append(split)
        return torch.randn(split.num_characters, 5, generator=torch.Generator().manual_seed(0))

    monkeypatch.setattr(state, "character_proportions", table)
    train, val = FakeSplit(), FakeSplit(seed=1)
    config = dataclasses.replace(TINY, loss=dataclasses.replace(TINY.loss, skeleton_proportion_weight=1.0))
    summary = fit(train, val, tmp_path / "r.pt", config, epochs=1)
    assert seen == [train]  # the training split's, not validation's (other characters)
    assert summary.history[-1]["train_skeleton_proportion"] > 0
    assert "val_skeleton_proportion" not in summary.history[-1]
    fit(train, val, tmp_path / "plain.pt", TINY, epochs=1)
    assert seen == [train]  # not asked for without the term
