"""What the retrieval tests share: the shipped network's motion-code encoder, four tracks and their index, and a
tiny motion world."""

from __future__ import annotations

import pytest

from pose_io.track import PoseTrack
from retarget.api import load_retargeter
from retarget.applications.search import MotionCodeEncoder, SearchIndex, from_sequences
from retarget.applications.search.features import track_features
from tests.retarget.applications.search.moving import moving_figure


@pytest.fixture(scope="package")
def encoder() -> MotionCodeEncoder:
    return MotionCodeEncoder(load_retargeter(None, "cpu"))


@pytest.fixture(scope="package")
def tracks() -> list[PoseTrack]:
    return [moving_figure(seed) for seed in range(4)]


@pytest.fixture(scope="package")
def index(encoder: MotionCodeEncoder, tracks: list[PoseTrack]) -> SearchIndex:
    sequences = [track_features(encoder, t) for t in tracks]
    return from_sequences(sequences, [f"t{k}" for k in range(len(tracks))], [t.fps for t in tracks],
                          [len(t) for t in tracks], encoder)


@pytest.fixture(scope="package")
def tiny_world(tmp_path_factory: pytest.TempPathFactory):
    """A motion world of four humanoid clips written here (see tests/retarget/world/humanoid.py)."""
    from retarget.world import MotionWorld
    from tests.retarget.world.humanoid import write_clip

    root = tmp_path_factory.mktemp("mocap")
    (root / "bandai").mkdir()
    for name in ("walk_normal_001", "bow_normal_001", "run_normal_001", "walk_fast_001"):
        write_clip(root / "bandai" / f"dataset-1_{name}.bvh.gz")
    return MotionWorld.build(root, tmp_path_factory.mktemp("cache"), n_train_characters=2, n_val_characters=2,
                             n_test_characters=2)  # fmt: skip
