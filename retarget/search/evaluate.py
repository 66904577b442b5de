"""How well motion retrieval works, measured on the motion world's test split where the truth is known.

Protocol (every choice from one seeded generator):

- Index: every clip of the split, whole, performed by ``pairs_per_clip`` of the split's characters, each seen
  from its own view bin (characters and views distinct within a clip; pitch uniform in +-``MAX_PITCH``).
- Query: ``length`` frames of a random window of the split (at a random start inside its clip, so not on the
  8-frame code grid) performed by a random character A seen from a random view V.
- Candidates: the index entries of another character AND another view than the query (at least two entries
  of the query's own clip always remain).
- Success: the top hit is the query's motion (same motion group: the same clip or another take of it); top-5:
  one of the five best tracks is. Localisation error: |hit start - query start| in frames, over the top hits
  that are the query's own clip (a periodic motion, a walk, may match one cycle away: the median and the
  share within 8 frames say more than the mean).
- Accuracy by view gap: top-1 over the queries whose nearest candidate performance of their motion is seen
  0-30, 30-60 or 60+ degrees of yaw away (the index holds ``pairs_per_clip`` of the 13 views of each clip, so
  most queries have one close by).

Both searches run the same normalised cross-correlation (:mod:`retarget.search.query`), on the network's
motion codes and on the raw-joint baseline (:class:`~retarget.search.features.JointEncoder`).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass

import numpy as np

from pose_io.errors import InputError
from pose_io.track import PoseTrack
from retarget.preprocess import body15_track
from retarget.search.features import (
    JointEncoder,
    MotionCodeEncoder,
    TrackEncoder,
    query_features,
    track_features,
)
from retarget.search.index import SearchIndex, from_sequences
from retarget.search.query import rank
from retarget.world import WorldSplit

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class RetrievalEvalConfig:
    """What the retrieval evaluation measures.

    Attributes:
        queries: number of queries.
        length: frames per query.
        pairs_per_clip: (character, view) performances of every clip in the index.
        top_k: hits looked at for the top-k accuracy.
        phase_step: frames between the query phases of the pass over the whole index (None: automatic, see
            :mod:`retarget.search.query`).
        seed: seed of every choice.
    """

    queries: int = 500
    length: int = 64
    pairs_per_clip: int = 4
    top_k: int = 5
    phase_step: int | None = None
    seed: int = 0

    def __post_init__(self) -> None:
        if self.queries < 1 or self.length < 16 or self.pairs_per_clip < 3 or self.top_k < 1:
            raise ValueError("need queries >= 1, length >= 16, pairs_per_clip >= 3 and top_k >= 1")


@dataclass(frozen=True)
class Entry:
    """One indexed performance: a whole clip on a character from a view."""

    clip: int
    group: str
    character: int
    view: int


@dataclass(frozen=True)
class Query:
    """One query: ``length`` frames from ``first`` of a clip, on a character from a view."""

    clip: int
    group: str
    first: int
    character: int
    view: int
    track: PoseTrack


@dataclass(frozen=True)
class MethodScores:
    """Accuracy of one feature kind."""

    top1: float
    topk: float
    same_clip_top1: float
    localisation_mean: float
    localisation_median: float
    localisation_within_8: float
    localised: int
    seconds_per_query: float
    top1_by_view_gap: dict[str, float]
    queries_by_view_gap: dict[str, int]


#: Bins of the yaw gap between a query and the nearest candidate performance of its motion (degrees).
VIEW_GAPS: tuple[tuple[float, float], ...] = ((0.0, 30.0), (30.0, 60.0), (60.0, 181.0))


def clip_windows(split: WorldSplit) -> list[int]:
    """The window that starts each clip of ``split`` (window index per clip, in clip order)."""
    first: dict[str, int] = {}
    for w, label in enumerate(split.window_labels):
        if label.start == 0 and label.path not in first:
            first[label.path] = w
    return list(first.values())


def _track(joints: np.ndarray, split: WorldSplit, fps: float) -> PoseTrack:
    return body15_track(joints, fps, (int(split.canvas_size[0]), int(split.canvas_size[1])))


def sample_entries(split: WorldSplit, config: RetrievalEvalConfig, rng: np.random.Generator) -> list[Entry]:
    """``pairs_per_clip`` (character, view) pairs per clip, characters and views distinct within the clip."""
    n = min(config.pairs_per_clip, split.num_characters, split.num_views)
    out = []
    for clip, w in enumerate(clip_windows(split)):
        chars = rng.choice(split.num_characters, n, replace=False)
        views = rng.choice(split.num_views, n, replace=False)
        out += [Entry(clip, split.window_labels[w].group, int(c), int(v)) for c, v in zip(chars, views)]
    return out


def sample_queries(
    split: WorldSplit, config: RetrievalEvalConfig, rng: np.random.Generator, fps: float
) -> list[Query]:
    """Random windows of the split, at random starts, on random characters from random views."""
    starts = clip_windows(split)
    clip_of = {split.window_labels[w].path: k for k, w in enumerate(starts)}
    eligible = [m for m, label in enumerate(split.window_labels) if label.clip_frames >= config.length]
    if not eligible:
        raise InputError(f"{split.name} split: no clip has {config.length} frames for a query; use a shorter --length")
    out = []
    for m in rng.choice(eligible, config.queries):
        label = split.window_labels[m]
        first = int(rng.integers(0, label.clip_frames - config.length + 1))
        character, view = int(rng.integers(split.num_characters)), int(rng.integers(split.num_views))
        joints = split.window(int(m), character, view, config.length, first - label.start, rng)  # [L, 15, 2]
        out.append(Query(clip_of[label.path], label.group, first, character, view, _track(joints, split, fps)))
    return out


def index_entries(
    split: WorldSplit, entries: list[Entry], encoder: TrackEncoder, fps: float, rng: np.random.Generator
) -> SearchIndex:
    """Encode every entry's whole clip with ``encoder`` (the pitches come from ``rng``)."""
    starts = clip_windows(split)
    sequences, paths, frames = [], [], []
    for e in entries:
        w = starts[e.clip]
        label = split.window_labels[w]
        joints = split.window(w, e.character, e.view, label.clip_frames, 0, rng)  # [F, 15, 2]
        sequences.append(track_features(encoder, _track(joints, split, fps), label.path))
        paths.append(f"{label.path}#{split.characters[e.character].name}@{split.views[e.view]:+.0f}")
        frames.append(label.clip_frames)
    return from_sequences(sequences, paths, [fps] * len(entries), frames, encoder)


def score_method(
    index: SearchIndex,
    encoder: TrackEncoder,
    entries: list[Entry],
    queries: list[Query],
    config: RetrievalEvalConfig,
    yaw_of: tuple[float, ...],
    progress: Callable[[int], None] | None = None,
) -> MethodScores:
    """Top-1 / top-k accuracy and localisation of one encoder's search over the queries.

    Args:
        yaw_of: the yaw (degrees) of every view bin, for the accuracy by view gap.
    """
    characters = np.array([e.character for e in entries])
    views = np.array([e.view for e in entries])
    yaws = np.array(yaw_of)[views]
    groups_of = np.array([e.group for e in entries])
    top1, topk, same, errors, seconds = 0, 0, 0, [], 0.0
    gap_hits, gap_counts = np.zeros(len(VIEW_GAPS)), np.zeros(len(VIEW_GAPS), dtype=np.int64)
    for q in queries:
        allowed = (characters != q.character) & (views != q.view)
        t0 = time.perf_counter()
        features, phases = query_features(encoder, q.track)
        hits = rank(index, features, phases, len(q.track) / encoder.fps, config.top_k, tracks=allowed,
                    phase_step=config.phase_step)  # fmt: skip
        seconds += time.perf_counter() - t0
        groups = [entries[h.track].group for h in hits]
        hit = bool(groups) and groups[0] == q.group
        top1 += hit
        gap = np.abs(yaws[allowed & (groups_of == q.group)] - yaw_of[q.view]).min()
        b = next(k for k, (lo, hi) in enumerate(VIEW_GAPS) if lo <= gap < hi)
        gap_hits[b] += hit
        gap_counts[b] += 1
        topk += q.group in groups
        if hits and entries[hits[0].track].clip == q.clip:
            same += 1
            errors.append(abs(hits[0].start - q.first))
        if progress is not None:
            progress(1)
    n = len(queries)
    return MethodScores(
        top1 / n, topk / n, same / n, float(np.mean(errors)) if errors else float("nan"),
        float(np.median(errors)) if errors else float("nan"),
        float(np.mean(np.array(errors) <= 8)) if errors else float("nan"), len(errors), seconds / n,
        {_gap_name(g): float(h / c) if c else float("nan") for g, h, c in zip(VIEW_GAPS, gap_hits, gap_counts)},
        {_gap_name(g): int(c) for g, c in zip(VIEW_GAPS, gap_counts)},
    )


def _gap_name(gap: tuple[float, float]) -> str:
    return f">={gap[0]:.0f}" if gap[1] > 180 else f"{gap[0]:.0f}-{gap[1]:.0f}"


def evaluate_retrieval(
    split: WorldSplit,
    encoder: MotionCodeEncoder,
    config: RetrievalEvalConfig = RetrievalEvalConfig(),
    fps: float = 30.0,
    progress: Callable[[int, int], None] | None = None,
) -> dict:
    """Retrieval accuracy of motion codes and of the raw-joint baseline on one split.

    Args:
        split: a motion-world split (the test split: motions and characters the network never saw).
        encoder: the network's motion encoder.
        config: the protocol's numbers.
        fps: the world's frame rate.
        progress: called as ``progress(done, total)`` over the queries of both methods.

    Returns:
        A JSON-ready dict: ``config``, counts (``clips``, ``groups``, ``tracks``, ``frames``) and per method
        (``motion``, ``joints``) the :class:`MethodScores` fields.
    """
    rng = np.random.default_rng(config.seed)
    entries = sample_entries(split, config, rng)
    queries = sample_queries(split, config, rng, fps)
    methods: dict[str, TrackEncoder] = {"motion": encoder, "joints": JointEncoder(encoder.retargeter.preprocess)}
    done, total = 0, len(queries) * len(methods)
    results: dict[str, dict] = {}
    frames = 0
    for name, enc in methods.items():
        # The same pitches for both methods: one generator per index, seeded alike.
        index = index_entries(split, entries, enc, fps, np.random.default_rng([config.seed, 1]))
        frames = index.num_frames

        def step(k: int) -> None:
            nonlocal done
            done += k
            if progress is not None:
                progress(done, total)

        results[name] = asdict(score_method(index, enc, entries, queries, config, split.views, step))
        log.info("retrieval with %s features: %s", name, results[name])
    return {
        "config": asdict(config),
        "split": split.name,
        "clips": len(clip_windows(split)),
        "groups": len({e.group for e in entries}),
        "tracks": len(entries),
        "frames": frames,
        "queries": len(queries),
        "methods": results,
    }


def markdown_table(doc: dict) -> str:
    """The result of :func:`evaluate_retrieval` as a markdown table."""
    k = doc["config"]["top_k"]
    names = {"motion": "motion codes (ours)", "joints": "raw joints / body height (baseline)"}
    gaps = list(next(iter(doc["methods"].values()))["top1_by_view_gap"])
    counts = next(iter(doc["methods"].values()))["queries_by_view_gap"]
    gap_head = " | ".join(f"top-1, view gap {g}° (n={counts[g]})" for g in gaps)
    lines = [
        (f"| features | top-1 | top-{k} | {gap_head} | top-1 same clip | localisation error, frames (mean / median"
         " / share <= 8) | ms / query |"),
        "|---|---|---|" + "---|" * len(gaps) + "---|---|---|",
    ]
    for name, m in doc["methods"].items():
        by_gap = " | ".join(f"{m['top1_by_view_gap'][g]:.3f}" for g in gaps)
        lines.append(
            f"| {names.get(name, name)} | {m['top1']:.3f} | {m['topk']:.3f} | {by_gap} | {m['same_clip_top1']:.3f} | "
            f"{m['localisation_mean']:.1f} / {m['localisation_median']:.0f} / {m['localisation_within_8']:.2f} "
            f"(n={m['localised']}) | "
            f"{1000 * m['seconds_per_query']:.1f} |"
        )
    return "\n".join(lines)
