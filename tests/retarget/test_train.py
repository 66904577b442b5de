import dataclasses
import shutil

import numpy as np
import pytest
import torch

from pose_io import BODY15, InputError, PoseTrack
from retarget.api import load_retargeter
from retarget.augment import AugmentConfig, combo_index
from retarget.checkpoint import load_checkpoint
from retarget.losses import objective
from retarget.model import RetargetNet, variant_config
from retarget.train import (
    CrossSamples,
    TrainConfig,
    batch_tensors,
    body_scales,
    character_heights,
    fit,
    mean_pose_height,
    retargeting_error,
    split_statistics,
    train,
    train_step,
)

_PARENT = {
    "neck": "mid_hip", "nose": "neck", "r_shoulder": "neck", "r_elbow": "r_shoulder", "r_wrist": "r_elbow",
    "l_shoulder": "neck", "l_elbow": "l_shoulder", "l_wrist": "l_elbow", "r_hip": "mid_hip", "r_knee": "r_hip",
    "r_ankle": "r_knee", "l_hip": "mid_hip", "l_knee": "l_hip", "l_ankle": "l_knee",
}
_OFFSET = {
    "neck": (0, 0.5, 0), "nose": (0, 0.2, 0.06), "r_shoulder": (-0.18, 0, 0), "r_elbow": (0, -0.28, 0),
    "r_wrist": (0, -0.25, 0), "l_shoulder": (0.18, 0, 0), "l_elbow": (0, -0.28, 0), "l_wrist": (0, -0.25, 0),
    "r_hip": (-0.1, 0, 0), "r_knee": (0, -0.42, 0), "r_ankle": (0, -0.4, 0), "l_hip": (0.1, 0, 0),
    "l_knee": (0, -0.42, 0), "l_ankle": (0, -0.4, 0),
}


class FakeSplit:
    """A tiny stand-in for a motion-world split: swinging stick figures.

    Motions differ in swing amplitude, frequency and travel; characters in limb lengths; views in the
    yaw of an orthographic camera. ``rng`` tilts the camera a little, like the world's random pitch.
    """

    def __init__(self, motions: int = 4, characters: int = 3, views: int = 3, seed: int = 0) -> None:
        rng = np.random.default_rng(seed)
        self.num_motions, self.num_characters, self.num_views = motions, characters, views
        self.motions = [
            {"amp": rng.uniform(0.2, 0.9), "freq": rng.uniform(0.05, 0.2), "phase": rng.uniform(0, 6),
             "speed": rng.uniform(-0.02, 0.02)}
            for _ in range(motions)
        ]
        self.characters = [{n: rng.uniform(0.8, 1.25) for n in _PARENT} for _ in range(characters)]
        self.yaws = np.linspace(-1.0, 1.0, views)
        self.views = tuple(float(np.degrees(y)) for y in self.yaws)

    def window(self, motion, character, view, length=64, offset=0, rng=None):
        t = np.arange(offset, offset + length, dtype=np.float64)
        m, ch = self.motions[motion], self.characters[character]
        swing = m["amp"] * np.sin(2 * np.pi * m["freq"] * t + m["phase"])
        angle = {"r_elbow": swing, "r_wrist": swing + 0.3, "l_elbow": -swing, "l_wrist": 0.3 - swing,
                 "r_knee": -swing, "r_ankle": -1.2 * swing, "l_knee": swing, "l_ankle": 1.2 * swing}
        pos = {"mid_hip": np.stack([m["speed"] * t, 0.82 + 0.03 * np.abs(swing), 0.5 * m["speed"] * t], -1)}
        for name in _PARENT:  # parents come first in this dict
            a = angle.get(name, np.zeros_like(t))
            off = np.array(_OFFSET[name]) * ch[name]
            rotated = np.stack([np.full_like(a, off[0]), np.cos(a) * off[1] - np.sin(a) * off[2],
                                np.sin(a) * off[1] + np.cos(a) * off[2]], -1)
            pos[name] = pos[_PARENT[name]] + rotated
        xyz = np.stack([pos[n] for n in BODY15.joints], axis=1)  # [T, 15, 3]
        yaw = self.yaws[view] + (rng.uniform(-0.1, 0.1) if rng is not None else 0.0)
        x = np.cos(yaw) * xyz[..., 0] + np.sin(yaw) * xyz[..., 2]
        return np.stack([256 + 110 * x, 420 - 110 * xyz[..., 1]], -1).astype(np.float32)


TINY = TrainConfig(batch_size=4, samples_per_epoch=8, val_samples=4, stats_windows=32)


def _batch(split, n=4, seed=0, variant="full"):
    samples = CrossSamples(split, 64, variant, n, seed)
    items = [samples.sample(0, i) for i in range(n)]
    return {
        "windows": torch.from_numpy(np.stack([it["windows"] for it in items])),
        "ids": torch.from_numpy(np.stack([it["ids"] for it in items])),
    }


def test_samples_are_deterministic_and_consistent():
    split = FakeSplit()
    samples = CrossSamples(split, 64, "full", 10, seed=3)
    a, b = samples.sample(2, 5), samples.sample(2, 5)
    np.testing.assert_array_equal(a["windows"], b["windows"])
    ids = a["ids"]
    assert (ids[0] != ids[1]).all()  # full model: motions, characters and views all differ
    w = a["windows"]
    # Every window is the world's window of its combination, seen through the view slot's camera.
    for k, (m, c, v) in enumerate([(m, c, v) for m in (0, 1) for c in (0, 1) for v in (0, 1)]):
        clean = split.window(ids[m, 0], ids[c, 1], ids[v, 2], length=64)
        assert np.abs(w[k] - clean).max() < 40  # within the small camera tilt
    assert not np.array_equal(w[combo_index(0, 0, 0)], w[combo_index(0, 1, 0)])
    skeleton = CrossSamples(split, 64, "skeleton", 10, seed=3).sample(0, 0)
    assert skeleton["ids"][0, 2] == skeleton["ids"][1, 2]  # no view encoder: one view
    np.testing.assert_array_equal(skeleton["windows"][combo_index(0, 1, 0)], skeleton["windows"][combo_index(0, 1, 1)])


# ids of samples 0-2 of epoch 1 of CrossSamples(FakeSplit(views=5), 64, "full", 200, seed=3), as drawn by the
# code before the frontal share existed.
PLAIN_IDS = [[[2, 2, 0], [1, 0, 2]], [[1, 2, 0], [2, 1, 4]], [[1, 2, 1], [2, 1, 2]]]


def test_a_frontal_share_draws_views_near_the_front_and_nothing_else_changes():
    split = FakeSplit(views=5)  # yaws -57, -29, 0, 29, 57 degrees: bins 1-3 are frontal
    plain = CrossSamples(split, 64, "full", 200, seed=3)
    frontal = CrossSamples(split, 64, "full", 200, seed=3, frontal=1.0)
    half = CrossSamples(split, 64, "full", 200, seed=3, frontal=0.5)
    # No share: the samples drawn before the option existed (ids recorded from that code), bit for bit.
    assert [plain.sample(1, i)["ids"].tolist() for i in range(3)] == PLAIN_IDS
    views = {name: np.array([d.sample(1, i)["ids"][:, 2] for i in range(200)]) for name, d in
             (("plain", plain), ("frontal", frontal), ("half", half))}  # fmt: skip
    assert set(np.unique(views["frontal"])) == {1, 2, 3}
    assert (views["frontal"][:, 0] != views["frontal"][:, 1]).all()  # still two views per sample
    outside = {name: np.isin(v, (0, 4)).any(axis=1).mean() for name, v in views.items()}
    assert 0.6 < outside["plain"] < 0.8  # 1 - 3/5 * 2/4 = 0.7
    assert 0.25 < outside["half"] < 0.45  # half of it
    # A window is still the split's window of its ids, through the view slot's camera (only views moved).
    sample = frontal.sample(0, 0)
    ids = sample["ids"]
    clean = split.window(ids[0, 0], ids[0, 1], ids[0, 2], length=64)
    assert np.abs(sample["windows"][combo_index(0, 0, 0)] - clean).max() < 40
    with pytest.raises(InputError, match="within 45 degrees"):
        CrossSamples(FakeSplit(views=2), 64, "full", 4, seed=0, frontal=0.5)
    config = TrainConfig(frontal_share=0.5)
    assert TrainConfig.from_dict(config.to_dict()) == config
    assert TrainConfig.from_dict({k: v for k, v in config.to_dict().items() if k != "frontal_share"}) == TrainConfig()


def test_one_training_step_lowers_the_loss():
    torch.manual_seed(0)
    split = FakeSplit()
    config = TrainConfig(augment=AugmentConfig(clip_lengths=(64,), scale_range=(1.0, 1.0), flip_prob=0.0,
                                               noise_std=0.0, drop_prob=0.0))
    stats = split_statistics(split, 64, 32, 0)
    batch = _batch(split)
    model = RetargetNet()
    optimizer = torch.optim.Adam(model.parameters(), lr=config.lr, amsgrad=True)

    def loss() -> float:
        model.eval()
        with torch.no_grad():
            inputs, targets = batch_tensors(batch["windows"], batch["ids"], stats, config, torch.Generator(), False)
            return float(objective(model, inputs, targets, stats, config.loss)["total"])

    before = loss()
    train_step(model, optimizer, batch, stats, config, torch.Generator().manual_seed(0))
    assert loss() < before


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


def _weights(path):
    return load_checkpoint(path).model.state_dict()


def test_resume_continues_exactly(tmp_path):
    split, val = FakeSplit(), FakeSplit(seed=1)
    fit(split, val, tmp_path / "whole.pt", TINY, epochs=2)
    # Stop after the first step (a zero budget), then resume to the end.
    first = fit(split, val, tmp_path / "parts.pt", TINY, epochs=2, minutes=0.0)
    assert first.stopped == "time" and first.steps == 1
    rest = fit(split, val, tmp_path / "parts.pt", TINY, epochs=2, resume=True)
    assert rest.epochs == 2 and rest.steps == 4
    whole, parts = _weights(tmp_path / "whole.pt"), _weights(tmp_path / "parts.pt")
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
    same = _weights(tmp_path / "short.pt")
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
        ends.append(_weights(tmp_path / "parts.pt"))
    mean, parts_mean = _weights(tmp_path / "mean.pt"), _weights(tmp_path / "parts_mean.pt")
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
    for key, value in _weights(tmp_path / "gap_mean.pt").items():
        torch.testing.assert_close(value, mean[key], rtol=0, atol=0)
    for option in ("best", "average"):
        with pytest.raises(InputError, match="would replace the checkpoint"):
            fit(split, val, tmp_path / "whole.pt", TINY, epochs=5, resume=True, **{option: tmp_path / "whole.pt"})
    # A run that went past the first averaged epoch without averaging cannot start now.
    fit(split, val, tmp_path / "plain.pt", TINY, epochs=2)
    with pytest.raises(InputError, match="start it later"):
        fit(split, val, tmp_path / "plain.pt", TINY, epochs=5, resume=True, average=tmp_path / "m2.pt", average_from=2)
    fit(split, val, tmp_path / "plain.pt", TINY, epochs=3, resume=True, average=tmp_path / "m2.pt", average_from=3)
    torch.testing.assert_close(_weights(tmp_path / "m2.pt"), _weights(tmp_path / "plain.pt"), rtol=0, atol=0)
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
    import dataclasses

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


def test_config_round_trip_and_validation():
    config = TrainConfig(variant="skeleton", augment=AugmentConfig(clip_lengths=(64, 32)))
    assert TrainConfig.from_dict(config.to_dict()) == config
    with pytest.raises(ValueError, match="unknown network variant"):
        TrainConfig(variant="huge")
    with pytest.raises(ValueError, match="window"):
        TrainConfig(window=32)
    assert variant_config(TrainConfig().variant).body_code == 16


def test_train_on_a_motion_world_built_from_mocap(shared_dir, tmp_path):
    mocap = tmp_path / "mocap"
    mocap.mkdir()
    for name in ("dataset-1/dataset-1_walk_normal_001", "dataset-1/dataset-1_bow_normal_001",
                 "dataset-2/dataset-2_walk_normal_001", "dataset-2/dataset-2_walk_normal_002"):
        shutil.copy(shared_dir / "mocap" / "bandai_namco" / f"{name}.bvh.gz", mocap)
    summary = train(mocap, tmp_path / "r.pt", cache_dir=tmp_path / "cache", config=TINY, epochs=1,
                    best=tmp_path / "best.pt")
    assert summary.epochs == 1 and "val_cross" in summary.history[0]
    assert load_checkpoint(tmp_path / "r.pt").training["epoch"] == 1
    assert summary.best_epoch == 1 and load_checkpoint(tmp_path / "best.pt").training is None


def test_real_tracks_are_read_from_openpose_folders(shared_dir, tmp_path):
    from retarget.train import read_real_tracks

    for clip in ("tall_man", "small_man"):
        shutil.copytree(shared_dir / "openpose_examples" / clip, tmp_path / "real" / clip)
    tracks = read_real_tracks(tmp_path / "real")
    assert [len(t) for t in tracks] == [121, 135]  # sorted by folder name
    assert len(read_real_tracks(tmp_path / "real" / "tall_man")) == 1
    (tmp_path / "empty").mkdir()
    with pytest.raises(InputError, match="no OpenPose folders"):
        read_real_tracks(tmp_path / "empty")


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


def test_characters_are_brought_to_one_height(tmp_path):
    split = FakeSplit(characters=3)
    heights = character_heights(split, 64, 4, seed=0)
    assert heights.shape == (3,) and np.ptp(heights) > 1.0  # the fake characters differ in size
    scales = body_scales(split, TINY, target=100.0)
    np.testing.assert_allclose(character_heights_scaled(split, scales), 100.0, rtol=0.05)
    assert body_scales(split, TrainConfig(body_normalise=False), 100.0) is None


def character_heights_scaled(split, scales):
    from pose_io.measures import skeleton_heights

    return np.array([np.median(skeleton_heights(np.stack([split.window(m, c, 0) * scales[c] for m in range(2)])))
                     for c in range(split.num_characters)])  # fmt: skip


def test_progress_is_a_callback_of_every_step_and_epoch(tmp_path):
    seen = []
    fit(FakeSplit(), FakeSplit(seed=1), tmp_path / "r.pt", TINY, epochs=2, progress=seen.append)
    steps = [p for p in seen if "epoch" not in p.losses]
    ends = [p for p in seen if "epoch" in p.losses]
    assert [p.global_step for p in steps] == [1, 2, 3, 4]
    assert [(p.epoch, p.step, p.steps_per_epoch) for p in ends] == [(1, 2, 2), (2, 2, 2)]
    assert "val_total" in ends[-1].losses and "total" in steps[0].losses


class CameraSplit(FakeSplit):
    """A FakeSplit that takes a camera spread: its pitch range widens the yaw tilt and perspective shrinks the
    figure, as a steep or near camera changes how tall a person looks."""

    def __init__(self) -> None:
        super().__init__()
        self.seen: list = []

    def window(self, motion, character, view, length=64, offset=0, rng=None, *, cameras=None):
        self.seen.append(cameras)
        out = super().window(motion, character, view, length, offset, rng)
        shrink = 0.6 if cameras is not None and cameras.perspective > 0 else 1.0
        return (out * shrink).astype(np.float32)


def test_a_camera_spread_reaches_the_split_and_windows_keep_the_height():
    from pose_io.measures import skeleton_heights
    from retarget.world import CameraSpread

    split = CameraSplit()
    scales = body_scales(split, TINY, target=100.0)
    split.seen.clear()
    spread = CameraSpread(max_pitch=30.0, perspective=1.0)
    samples = CrossSamples(split, 64, "full", 4, seed=0, scales=scales, cameras=spread, height=100.0)
    windows = samples.sample(0, 0)["windows"]
    assert split.seen and all(c == spread for c in split.seen)
    # Each window brought to the target height by its own skeleton height, as inference brings a track.
    np.testing.assert_allclose(skeleton_heights(windows), 100.0, rtol=1e-4)
    # The world's cameras: the split is called as before and the characters' own scales apply.
    split.seen.clear()
    plain = CrossSamples(split, 64, "full", 4, seed=0, scales=scales).sample(0, 0)["windows"]
    assert split.seen == [None] * len(split.seen)
    assert np.ptp(skeleton_heights(plain)) > 0.01  # per character, not per window
    with pytest.raises(ValueError, match="target height"):
        CrossSamples(split, 64, "full", 4, seed=0, scales=scales, cameras=spread)


def test_config_keeps_its_camera_spread_and_old_configs_get_the_worlds():
    from retarget.world import CameraSpread

    config = TrainConfig(cameras=CameraSpread(max_pitch=25.0, perspective=0.5))
    assert TrainConfig.from_dict(config.to_dict()) == config
    old = TrainConfig().to_dict()
    del old["cameras"]
    assert TrainConfig.from_dict(old).cameras == CameraSpread()


def test_fit_feeds_the_training_characters_proportions_to_the_skeleton_proportion_term(tmp_path, monkeypatch):
    from retarget.training import loop

    seen = []

    def table(split):  # the fake split's characters are not Skeletons; any [C, P] table will do
        seen.append(split)
        return torch.randn(split.num_characters, 5, generator=torch.Generator().manual_seed(0))

    monkeypatch.setattr(loop, "character_proportions", table)
    train, val = FakeSplit(), FakeSplit(seed=1)
    config = dataclasses.replace(TINY, loss=dataclasses.replace(TINY.loss, skeleton_proportion_weight=1.0))
    summary = fit(train, val, tmp_path / "r.pt", config, epochs=1)
    assert seen == [train]  # the training split's, not validation's (other characters)
    assert summary.history[-1]["train_skeleton_proportion"] > 0
    assert "val_skeleton_proportion" not in summary.history[-1]
    fit(train, val, tmp_path / "plain.pt", TINY, epochs=1)
    assert seen == [train]  # not asked for without the term


def test_character_proportions_are_standardised_log_ratios():
    from types import SimpleNamespace

    from retarget.training.step import character_proportions
    from retarget.world.characters import make_skeleton

    bodies = [make_skeleton(1.8), make_skeleton(1.2), make_skeleton(1.7, legs=1.1, head=0.9)]
    table = character_proportions(SimpleNamespace(characters=bodies))
    assert table.shape == (3, len(bodies[0].lengths)) and table.dtype == torch.float32
    torch.testing.assert_close(table.mean(dim=0), torch.zeros(table.shape[1]), atol=1e-5, rtol=0)
    logs = np.log(np.array([b.array / b.height for b in bodies]))
    expected = (logs - logs.mean(axis=0)) / (logs.std(axis=0) + 1e-9)
    np.testing.assert_allclose(table.numpy(), expected, atol=1e-5)
