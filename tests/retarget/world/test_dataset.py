"""The motion world dataset on a tiny world, and `clone world build`."""

from __future__ import annotations

import itertools
import pickle
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from pose_io import atomic
from pose_io.errors import InputError
from pose_io.layouts import BODY15
from retarget.inference.windows import strided_starts
from retarget.world import (
    MAX_PITCH,
    NAMED_CHARACTERS,
    WORLD_JOINTS,
    CameraSpread,
    MotionWorld,
    facing_angle,
    project,
)
from retarget.world import build as build_module
from retarget.world.build import assign_splits, motion_group
from tests.retarget.world.humanoid import write_clip

J = WORLD_JOINTS.index
TINY_FILES = (
    "bandai_namco/dataset-1/dataset-1_walk_normal_001.bvh.gz",
    "bandai_namco/dataset-1/dataset-1_bow_normal_001.bvh.gz",
    "bandai_namco/dataset-2/dataset-2_walk_normal_001.bvh.gz",
    "bandai_namco/dataset-2/dataset-2_walk_normal_002.bvh.gz",
)
SMALL = {"n_train_characters": 3, "n_val_characters": 2, "n_test_characters": 2}


@pytest.fixture(scope="module")
def tiny_mocap(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Four clips: two motions of dataset-1 and two takes of one motion of dataset-2."""
    root = tmp_path_factory.mktemp("mocap")
    for rel in TINY_FILES:
        dest = root / "bandai" / Path(rel).name
        dest.parent.mkdir(parents=True, exist_ok=True)
        write_clip(dest)
    return root


@pytest.fixture(scope="module")
def tiny_world(tiny_mocap: Path, tmp_path_factory: pytest.TempPathFactory) -> MotionWorld:
    return MotionWorld.build(tiny_mocap, tmp_path_factory.mktemp("cache"), **SMALL)


def test_splits_share_no_motion_and_no_character(tiny_world: MotionWorld) -> None:
    splits = {name: tiny_world.split(name) for name in ("train", "val", "test")}
    groups = {name: {lab.group for lab in s.window_labels} for name, s in splits.items()}
    paths = {name: {lab.path for lab in s.window_labels} for name, s in splits.items()}
    for a, b in itertools.combinations(splits, 2):
        assert not groups[a] & groups[b], (a, b)
        assert not paths[a] & paths[b], (a, b)
    # The two takes of dataset-2 walk_normal are one motion: they share a split.
    assert any(len(p) == 2 for p in paths.values())
    lengths = {name: {c.lengths for c in s.characters} for name, s in splits.items()}
    for a, b in itertools.combinations(splits, 2):
        assert not lengths[a] & lengths[b]
    assert set(NAMED_CHARACTERS) <= set(splits["test"].character_names)
    assert not set(NAMED_CHARACTERS) & set(splits["train"].character_names)
    assert [splits[n].num_characters for n in splits] == [3, 2, 2 + len(NAMED_CHARACTERS)]


def test_summary_counts(tiny_world: MotionWorld) -> None:
    summary = tiny_world.summary()
    for name, s in summary["splits"].items():
        split = tiny_world.split(name)
        assert s["windows"] == split.num_motions == len(split.window_labels) > 0
        assert s["characters"] == split.num_characters
        assert s["views"] == split.num_views == 13
        assert s["samples"] == s["windows"] * s["characters"] * 13
    assert sum(s["clips"] for s in summary["splits"].values()) == 4
    assert summary["cache"] == str(tiny_world.path)


def test_windows_follow_the_framing_rule(tiny_world: MotionWorld) -> None:
    split = tiny_world.split("train")
    front = split.views.index(0.0)
    for motion in range(split.num_motions):
        label = split.window_labels[motion]
        assert 0 <= label.start and label.start + 64 <= label.clip_frames
        win = split.window(motion, 1, front)
        assert win.shape == (64, 15, 2) and win.dtype == np.float32
        assert win[0, BODY15.index("mid_hip"), 0] == pytest.approx(256.0, abs=1e-3)
        # Some foot is on the ground line (0.9 * 512) in the first frame.
        feet = win[0, [BODY15.index("l_ankle"), BODY15.index("r_ankle")], 1].max()
        assert 440 < feet < 470
    # The 2D window is the projection of the 3D window.
    pos = split.window3d(0, 2)
    assert pos.shape == (64, 18, 3)
    np.testing.assert_allclose(pos[0, J("mid_hip"), [0, 2]], 0.0, atol=1e-6)
    xy, _ = project(pos, split.camera(4, 3.0), facing_angle(pos))
    np.testing.assert_allclose(split.window(0, 2, 4, pitch_deg=3.0), xy[:, : len(BODY15)], atol=1e-4)


def test_characters_and_views_change_the_window(tiny_world: MotionWorld) -> None:
    split = tiny_world.split("test")
    a = split.window(0, 0, 6)
    assert not np.allclose(a, split.window(0, 1, 6))
    assert not np.allclose(a, split.window(0, 0, 0))
    # A random pitch within +-10 degrees; None gives pitch 0.
    rng = np.random.default_rng(0)
    jittered = split.window(0, 0, 6, rng=rng)
    assert not np.allclose(a, jittered)
    np.testing.assert_array_equal(a, split.window(0, 0, 6, rng=None))
    batch = split.windows([0, 0], [0, 1], [6, 6])
    np.testing.assert_array_equal(batch[0], a)
    # Longer or shifted windows must stay inside the clip.
    label = split.window_labels[0]
    with pytest.raises(ValueError, match="outside clip"):
        split.window(0, 0, 6, length=64, offset=label.clip_frames - label.start - 63)
    assert split.window(0, 0, 6, length=32, offset=16).shape == (32, 15, 2)
    with pytest.raises(IndexError):
        split.window(split.num_motions, 0, 0)


def test_split_pickles_by_reference(tiny_world: MotionWorld) -> None:
    split = tiny_world.split("val")
    blob = pickle.dumps(split)
    assert len(blob) < 200_000  # the folder and metadata, not the arrays
    again = pickle.loads(blob)
    np.testing.assert_array_equal(again.window(0, 1, 5), split.window(0, 1, 5))


def test_second_build_comes_from_the_cache(
    tiny_mocap: Path, tiny_world: MotionWorld, monkeypatch: pytest.MonkeyPatch
) -> None:
    def no_loading(*args: object, **kwargs: object) -> None:
        raise AssertionError("the cache was not used")

    monkeypatch.setattr(build_module, "load_motion", no_loading)
    again = MotionWorld.build(tiny_mocap, tiny_world.path.parent, **SMALL)
    assert again.path == tiny_world.path
    np.testing.assert_array_equal(again.split("val").window(0, 0, 3), tiny_world.split("val").window(0, 0, 3))
    with pytest.raises(AssertionError, match="cache"):
        MotionWorld.build(tiny_mocap, tiny_world.path.parent, **dict(SMALL, seed=1))


def test_extra_characters_join_training_only(tiny_mocap: Path, tiny_world: MotionWorld) -> None:
    wide = MotionWorld.build(tiny_mocap, tiny_world.path.parent, **SMALL, extra_train_characters=4, extra_spread=3.0)
    assert wide.path != tiny_world.path
    train, base = wide.split("train"), tiny_world.split("train")
    assert train.num_characters == 3 + 4 and train.characters[:3] == base.characters
    assert all(name.startswith("train_extra_") for name in train.character_names[3:])
    for name in ("val", "test"):  # what the network is measured on does not move
        assert wide.split(name).characters == tiny_world.split(name).characters
        np.testing.assert_array_equal(wide.split(name).window(0, 1, 2), tiny_world.split(name).window(0, 1, 2))

    def spread(skeletons: tuple) -> float:
        lengths = np.array([s.lengths for s in skeletons]) / np.array([[s.height] for s in skeletons])
        return float(np.log(lengths).std(axis=0).mean())

    assert spread(train.characters[3:]) > spread(train.characters[:3])


def test_world_build_refuses_what_the_disk_cannot_hold(
    tiny_mocap: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(atomic.shutil, "disk_usage", lambda path: type("U", (), {"free": 2**20})())
    with pytest.raises(InputError, match="the motion world needs .* GiB .* fewer --extra-characters"):
        MotionWorld.build(tiny_mocap, tmp_path / "cache", **SMALL)
    assert not any((tmp_path / "cache").glob("world-*"))


def test_build_errors(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="no such folder"):
        MotionWorld.build(tmp_path / "none", tmp_path / "cache")
    (tmp_path / "empty").mkdir()
    with pytest.raises(InputError, match="no .bvh"):
        MotionWorld.build(tmp_path / "empty", tmp_path / "cache")
    one = tmp_path / "one"
    one.mkdir()
    write_clip(one / Path(TINY_FILES[0]).name)
    with pytest.raises(InputError, match="too few distinct motions"):
        MotionWorld.build(one, tmp_path / "cache", **SMALL)
    assert not any((tmp_path / "cache").glob("world-*"))  # nothing half-written


def test_motion_groups_and_split_assignment() -> None:
    assert motion_group("cmu/01_01.bvh.gz") == motion_group("x/01_01.amc") == motion_group("002/001_01.bvh") == "cmu:1_1"
    assert motion_group("b/dataset-2_walk_normal_002.bvh.gz") == "dataset-2_walk_normal"
    assert strided_starts(100, 64, 32) == [0, 32, 36]
    assert strided_starts(96, 64, 32) == [0, 32] and strided_starts(50, 64, 32) == []
    from retarget.world.config import WorldConfig

    groups = [f"g{k}" for k in range(20)] + ["g0"]
    sources = ["a"] * 21
    frames = [100] * 21
    split = assign_splits(groups, sources, frames, WorldConfig())
    assert split[0] == split[-1]  # same group, same split
    assert {"train", "val", "test"} == set(split)
    assert split.count("train") > 12


def test_cli_world_build(tiny_mocap: Path, tmp_path: Path) -> None:
    from clone.cli.main import app

    runner = CliRunner()
    args = ["world", "build", "--mocap", str(tiny_mocap), "--cache", str(tmp_path / "cache"),
            "--train-characters", "2", "--val-characters", "1", "--test-characters", "1"]
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    assert "train" in result.output and "val" in result.output and "cache:" in result.output
    assert any((tmp_path / "cache").glob("world-*/meta.json"))
    result = runner.invoke(app, ["world", "build", "--mocap", str(tmp_path / "missing")])
    assert result.exit_code == 2 and "error:" in result.output


def test_default_camera_spread_draws_as_the_world_always_has(tiny_world: MotionWorld) -> None:
    split = tiny_world.split("train")
    jittered = split.window(0, 0, 6, rng=np.random.default_rng(5))
    by_pitch = split.window(0, 0, 6, pitch_deg=float(np.random.default_rng(5).uniform(-MAX_PITCH, MAX_PITCH)))
    np.testing.assert_array_equal(jittered, by_pitch)
    np.testing.assert_array_equal(jittered, split.window(0, 0, 6, rng=np.random.default_rng(5), cameras=CameraSpread()))


def test_wider_pitch_and_perspective_cameras(tiny_world: MotionWorld) -> None:
    split = tiny_world.split("train")
    steep = CameraSpread(max_pitch=40.0)
    pitches = [steep.draw(np.random.default_rng(s), 1)[0][0] for s in range(200)]
    assert max(np.abs(pitches)) > 30 and max(np.abs(pitches)) <= 40
    near = CameraSpread(perspective=1.0, near=2.0, far=2.0)
    pitch, distance = near.draw(np.random.default_rng(1), 4)
    np.testing.assert_array_equal(distance, 2.0)
    weak = split.window(0, 0, 6, pitch_deg=float(pitch[0]))
    seen = split.window(0, 0, 6, rng=np.random.default_rng(1), cameras=near)
    assert seen.shape == weak.shape and seen.dtype == np.float32 and np.isfinite(seen).all()
    # Seen from 2 m in front of the face (yaw 0, pitch ~0 here), the head comes out bigger than the feet: the
    # nose-neck segment grows against the weak-perspective view, the shins shrink.
    flat = CameraSpread(max_pitch=0.0, perspective=1.0, near=2.0, far=2.0)
    close = split.window(0, 0, split.views.index(0.0), rng=np.random.default_rng(0), cameras=flat)
    far = split.window(0, 0, split.views.index(0.0), pitch_deg=0.0)
    head = (BODY15.index("nose"), BODY15.index("neck"))
    shin = (BODY15.index("l_knee"), BODY15.index("l_ankle"))

    def seg(w: np.ndarray, pair: tuple[int, int]) -> float:
        return float(np.median(np.linalg.norm(w[:, pair[0]] - w[:, pair[1]], axis=-1)))

    assert seg(close, head) / seg(far, head) > seg(close, shin) / seg(far, shin) * 1.05
    # The aim point keeps its weak-perspective place: far cameras converge to the world's projection.
    distant = CameraSpread(max_pitch=0.0, perspective=1.0, near=900.0, far=900.0)
    np.testing.assert_allclose(
        split.window(0, 0, 6, rng=np.random.default_rng(0), cameras=distant), split.window(0, 0, 6, pitch_deg=0.0),
        atol=0.5,
    )


@pytest.mark.parametrize("bad", [{"max_pitch": 90.0}, {"perspective": 1.5}, {"near": 0.1}, {"near": 9.0, "far": 3.0}])
def test_camera_spread_rejects_bad_settings(bad: dict) -> None:
    with pytest.raises(ValueError):
        CameraSpread(**bad)
