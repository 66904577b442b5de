"""Motion retrieval (Aberman et al. 2019, Sec. 7): find the same motion in a collection of pose tracks,
whoever performs it and from whichever side it is filmed.

    encoder = MotionCodeEncoder(load_retargeter())
    index, skipped = build_index(["tracks/"], encoder)       # every track encoded once
    save_index(index, "tracks.index")
    hits = search(load_index("tracks.index"), encoder, query_track, top_k=5)

Modules: :mod:`~retarget.applications.search.features` (motion codes and the raw-joint baseline),
:mod:`~retarget.applications.search.index` (the index and its file), :mod:`~retarget.applications.search.query` (one-pass normalised
cross-correlation and the hits), :mod:`~retarget.applications.search.protocol` (the evaluation's index entries, queries and
candidates), :mod:`~retarget.applications.search.evaluate` (accuracy on the motion world's test split).
"""

from retarget.applications.search.features import (
    ENCODE_FPS,
    JointEncoder,
    MotionCodeEncoder,
    TrackEncoder,
    model_digest,
)
from retarget.applications.search.index import (
    FORMAT_VERSION,
    SearchIndex,
    Skipped,
    build_index,
    from_sequences,
    load_index,
    save_index,
)
from retarget.applications.search.query import Match, check_encoder, correlate, rank, search

__all__ = [
    "ENCODE_FPS",
    "FORMAT_VERSION",
    "JointEncoder",
    "Match",
    "MotionCodeEncoder",
    "SearchIndex",
    "Skipped",
    "TrackEncoder",
    "build_index",
    "check_encoder",
    "correlate",
    "from_sequences",
    "load_index",
    "model_digest",
    "rank",
    "save_index",
    "search",
]
