"""What the retrieval tests share: the shipped network's motion-code encoder, four tracks and their index."""

from __future__ import annotations

import pytest

from pose_io.track import PoseTrack
from retarget.api import load_retargeter
from retarget.search import MotionCodeEncoder, SearchIndex, from_sequences
from retarget.search.features import track_features
from tests.retarget.search.moving import moving_figure


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
