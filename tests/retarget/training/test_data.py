"""retarget.training.data: cross samples, the frontal share, body scales, camera spreads, source balance."""

from __future__ import annotations

import numpy as np
import pytest

from pose_io import InputError
from retarget.training.augment import combo_index
from retarget.training.config import TrainConfig
from retarget.training.data import CrossSamples, body_scales, character_heights, source_weights, window_source
from retarget.world.split import WindowLabel
from tests.retarget.training.fake_split import TINY, CameraSplit, FakeSplit


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


@pytest.fixture(scope="module")
def tiny_split(tmp_path_factory):
    from retarget.world import MotionWorld
    from tests.retarget.world.test_dataset import SMALL, TINY_FILES, write_clip

    root = tmp_path_factory.mktemp("mocap")
    for rel in TINY_FILES:
        dest = root / "bandai" / rel.rsplit("/", 1)[-1]
        dest.parent.mkdir(parents=True, exist_ok=True)
        write_clip(dest)
    return MotionWorld.build(root, tmp_path_factory.mktemp("cache"), **SMALL).split("train")


def test_turning_samples_keep_their_draws_and_turn_every_window_of_a_motion_alike(tiny_split):
    from retarget.world.turns import facing_change

    plain = CrossSamples(tiny_split, 64, "full", 20, seed=3)
    turned = CrossSamples(tiny_split, 64, "full", 20, seed=3, turns=1.0)
    none = CrossSamples(tiny_split, 64, "full", 20, seed=3, turns=0.0)
    for i in range(3):
        a, b, c = plain.sample(1, i), turned.sample(1, i), none.sample(1, i)
        np.testing.assert_array_equal(a["ids"], b["ids"])  # the same motions, characters and views
        np.testing.assert_array_equal(a["windows"], c["windows"])  # a share of 0 draws nothing new
        assert not np.allclose(a["windows"], b["windows"])
        np.testing.assert_array_equal(b["windows"], turned.sample(1, i)["windows"])  # deterministic
    sample = turned.sample(0, 0)
    w = sample["windows"]  # [8, T, 15, 2]
    # Windows of one motion on two characters seen from one view turn alike: the shoulder axis keeps the
    # same on-screen direction sign frame by frame.
    from retarget.network.preprocess import LAYOUT

    r, left = LAYOUT.index("r_shoulder"), LAYOUT.index("l_shoulder")
    sign = np.sign(w[:, :, left, 0] - w[:, :, r, 0])  # [8, T]
    assert (sign[combo_index(0, 0, 0)] == sign[combo_index(0, 1, 0)]).mean() > 0.9
    assert facing_change(np.zeros((1, 2, 18, 3))).shape == (1,)
    with pytest.raises(ValueError, match="share"):
        CrossSamples(tiny_split, 64, "full", 4, seed=0, turns=1.5)
    config = TrainConfig(turn_share=0.3, turn_range=(90.0, 180.0))
    assert TrainConfig.from_dict(config.to_dict()) == config


def test_spliced_and_bent_samples_keep_their_draws_and_vary_the_motion(tiny_split):
    plain = CrossSamples(tiny_split, 64, "full", 20, seed=3)
    spliced = CrossSamples(tiny_split, 64, "full", 20, seed=3, splices=1.0)
    bent = CrossSamples(tiny_split, 64, "full", 20, seed=3, bend_deg=8.0)
    for i in range(3):
        a, b, c = plain.sample(1, i), spliced.sample(1, i), bent.sample(1, i)
        np.testing.assert_array_equal(a["ids"], b["ids"])
        np.testing.assert_array_equal(a["ids"], c["ids"])
        assert not np.allclose(a["windows"], b["windows"]) and not np.allclose(a["windows"], c["windows"])
        np.testing.assert_array_equal(b["windows"], spliced.sample(1, i)["windows"])  # deterministic
        np.testing.assert_array_equal(c["windows"], bent.sample(1, i)["windows"])
        assert np.isfinite(b["windows"]).all() and np.isfinite(c["windows"]).all()
    with pytest.raises(ValueError, match="share"):
        CrossSamples(tiny_split, 64, "full", 4, seed=0, splices=2.0)
    with pytest.raises(ValueError, match="bend"):
        TrainConfig(bend_deg=90.0)
    config = TrainConfig(splice_share=0.3, bend_deg=8.0)
    assert TrainConfig.from_dict(config.to_dict()) == config


def _labelled(split: FakeSplit, sources: list[str]) -> FakeSplit:
    """``split`` with a window label per motion, motion i from the folder ``sources[i]``."""
    split.window_labels = tuple(WindowLabel(f"clip{i}", f"{src}/clip{i}.bvh.gz", 0, f"g{i}", 200)
                                for i, src in enumerate(sources))  # fmt: skip
    return split


def test_a_source_balance_draws_small_sources_more_often_and_none_keeps_the_draws():
    split = _labelled(FakeSplit(motions=10), ["big"] * 8 + ["small"] * 2)
    plain = CrossSamples(split, 64, "full", 400, seed=2)
    unbalanced = CrossSamples(split, 64, "full", 400, seed=2, source_balance=0.0)
    balanced = CrossSamples(split, 64, "full", 400, seed=2, source_balance=1.0)
    for i in range(3):
        np.testing.assert_array_equal(plain.sample(0, i)["ids"], unbalanced.sample(0, i)["ids"])
    def small_share(samples):
        return np.mean([samples.sample(0, i)["ids"][:, 0] >= 8 for i in range(400)])
    # Two distinct motions per sample: every window alike gives the small source 20 % of the draws; every
    # source alike lifts it towards a half (less, as the two motions of a sample differ).
    assert 0.15 < small_share(plain) < 0.25
    assert 0.38 < small_share(balanced) < 0.52
    with pytest.raises(ValueError, match="source_balance"):
        CrossSamples(split, 64, "full", 4, seed=0, source_balance=1.5)
    with pytest.raises(ValueError, match="source_balance"):
        TrainConfig(source_balance=-0.1)
    config = TrainConfig(source_balance=0.5)
    assert TrainConfig.from_dict(config.to_dict()) == config


def test_source_weights_go_as_the_count_to_a_power():
    labels = [WindowLabel("a", p, 0, "g", 100) for p in ["x/a.bvh"] * 4 + ["y/sub/b.bvh"] + ["c.bvh"]]
    assert [window_source(label) for label in labels[3:]] == ["x", "y", ""]
    half = source_weights(labels, 0.5)
    np.testing.assert_allclose(half.sum(), 1.0)
    np.testing.assert_allclose(half[:4].sum() / half[4], 2.0)  # the sources' shares as sqrt(4) : sqrt(1)
    np.testing.assert_allclose(source_weights(labels, 0.0), np.full(6, 1 / 6))
    even = source_weights(labels, 1.0)
    np.testing.assert_allclose([even[:4].sum(), even[4], even[5]], [1 / 3] * 3)
