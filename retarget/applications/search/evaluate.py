"""How well motion retrieval works, measured on the motion world's test split where the truth is known.

The protocol (index entries, queries, each query's candidates: :mod:`retarget.applications.search.protocol`) in short: every
clip of the split is indexed whole, performed by ``pairs_per_clip`` characters from as many view bins; a query is
a random ``length``-frame window performed by character A seen from view V; its candidates are the entries of
another character seen at least ``min_view_gap`` degrees of yaw from V.

- Success: the top hit is the query's motion (same motion group: the same clip or another take of it); top-5:
  one of the five best tracks is. Localisation error: |hit start - query start| in frames, over the top hits
  that are the query's own clip (a periodic motion, a walk, may match one cycle away: the median and the
  share within 8 frames say more than the mean).
- Accuracy by view gap: top-1 over the queries whose nearest candidate performance of their motion is seen
  0-30, 30-60, 60-90 or 90+ degrees of yaw away.

Both searches run the same normalised cross-correlation (:mod:`retarget.applications.search.query`), on the network's
motion codes and on the raw-joint baseline (:class:`~retarget.applications.search.features.JointEncoder`).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass

import numpy as np

from retarget.applications.search.features import (
    JointEncoder,
    MotionCodeEncoder,
    TrackEncoder,
    query_features,
    track_features,
)
from retarget.applications.search.index import SearchIndex, from_sequences
from retarget.applications.search.protocol import (
    Entry,
    Query,
    RetrievalEvalConfig,
    candidate_mask,
    clip_windows,
    pose_track,
    sample_entries,
    sample_queries,
    yaw_gap,
)
from retarget.applications.search.query import rank
from retarget.world import WorldSplit

__all__ = [
    "MethodScores",
    "RetrievalEvalConfig",
    "evaluate_retrieval",
    "markdown_table",
    "score_method",
    "summary",
]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class MethodScores:
    """Accuracy of one feature kind; a measure no query reaches (no localised hit, an empty view gap) is None."""

    top1: float
    topk: float
    same_clip_top1: float
    localisation_mean: float | None
    localisation_median: float | None
    localisation_within_8: float | None
    localised: int
    seconds_per_query: float
    top1_by_view_gap: dict[str, float | None]
    queries_by_view_gap: dict[str, int]


#: Bins of the yaw gap between a query and the nearest candidate performance of its motion (degrees).
VIEW_GAPS: tuple[tuple[float, float], ...] = ((0.0, 30.0), (30.0, 60.0), (60.0, 90.0), (90.0, 181.0))


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
        sequences.append(track_features(encoder, pose_track(joints, split, fps), label.path))
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
    gap = config.min_view_gap
    top1, topk, same, errors, seconds = 0, 0, 0, [], 0.0
    gap_hits, gap_counts = np.zeros(len(VIEW_GAPS)), np.zeros(len(VIEW_GAPS), dtype=np.int64)
    for q in queries:
        allowed = candidate_mask(characters, views, q.character, q.view, yaw_of, gap)
        t0 = time.perf_counter()
        features, phases = query_features(encoder, q.track)
        hits = rank(index, features, phases, len(q.track) / encoder.fps, config.top_k, tracks=allowed,
                    phase_step=config.phase_step)  # fmt: skip
        seconds += time.perf_counter() - t0
        groups = [entries[h.track].group for h in hits]
        hit = bool(groups) and groups[0] == q.group
        top1 += hit
        # Never empty: every query keeps candidates of its own clip (retarget.applications.search.protocol).
        nearest = yaw_gap(yaws[allowed & (groups_of == q.group)], yaw_of[q.view]).min()
        b = next(k for k, (lo, hi) in enumerate(VIEW_GAPS) if lo <= nearest < hi)
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
        top1 / n, topk / n, same / n, float(np.mean(errors)) if errors else None,
        float(np.median(errors)) if errors else None,
        float(np.mean(np.array(errors) <= 8)) if errors else None, len(errors), seconds / n,
        # None (JSON null) where no query falls: NaN is no JSON and never equals itself.
        {_gap_name(g): float(h / c) if c else None for g, h, c in zip(VIEW_GAPS, gap_hits, gap_counts)},
        {_gap_name(g): int(c) for g, c in zip(VIEW_GAPS, gap_counts)},
    )


def _gap_name(gap: tuple[float, float]) -> str:
    return f">={gap[0]:.0f}" if gap[1] > 180 else f"{gap[0]:.0f}-{gap[1]:.0f}"


def evaluate_retrieval(
    split: WorldSplit,
    encoder: MotionCodeEncoder,
    config: RetrievalEvalConfig | None = None,
    fps: float = 30.0,
    progress: Callable[[int, int], None] | None = None,
) -> dict:
    """Retrieval accuracy of motion codes and of the raw-joint baseline on one split.

    Args:
        split: a motion-world split (the test split: motions and characters the network never saw).
        encoder: the network's motion encoder.
        config: the protocol's numbers (default: ``RetrievalEvalConfig()``).
        fps: the world's frame rate.
        progress: called as ``progress(done, total)`` over the queries of both methods.

    Returns:
        A JSON-ready dict: ``config``, counts (``clips``, ``groups``, ``tracks``, ``frames``, ``queries``, and
        ``redrawn``: query draws thrown away for keeping too few candidates), per method (``motion``,
        ``joints``) the :class:`MethodScores` fields, and ``motion_over_joints``: the ratios of their top-1
        and top-k accuracies.
    """
    config = RetrievalEvalConfig() if config is None else config
    rng = np.random.default_rng(config.seed)
    entries = sample_entries(split, config, rng)
    queries, redrawn = sample_queries(split, config, entries, rng, fps)
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
        "redrawn": redrawn,
        "methods": results,
        "motion_over_joints": {k: _ratio(results["motion"][k], results["joints"][k]) for k in ("top1", "topk")},
    }


def _ratio(a: float, b: float) -> float | None:
    return a / b if b > 0 else None  # None (JSON null): the baseline found nothing


def summary(doc: dict) -> str:
    """What :func:`evaluate_retrieval` measured on, and the ratios of the two methods, in two lines."""
    c = doc["config"]
    r = {k: "n/a" if v is None else f"{v:.2f}x" for k, v in doc["motion_over_joints"].items()}
    return (
        f"{doc['split']} split: {doc['tracks']} indexed performances of {doc['clips']} clips ({doc['groups']} "
        f"motions, {doc['frames']:,} frames); {doc['queries']} queries of {c['length']} frames, candidates "
        f"another character >= {c['min_view_gap']:g} degrees of yaw away ({doc['redrawn']} draws redrawn)\n"
        f"motion codes / raw joints: top-1 {r['top1']}, top-{c['top_k']} {r['topk']}"
    )


def markdown_table(doc: dict) -> str:
    """The result of :func:`evaluate_retrieval` as a markdown table."""
    k = doc["config"]["top_k"]
    names = {"motion": "motion codes (ours)", "joints": "raw joints / body height (baseline)"}
    counts = next(iter(doc["methods"].values()))["queries_by_view_gap"]
    gaps = [g for g, n in counts.items() if n]  # a gap no query has (below min_view_gap) says nothing
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
            f"{_localisation(m)} (n={m['localised']}) | "
            f"{1000 * m['seconds_per_query']:.1f} |"
        )
    return "\n".join(lines)


def _localisation(m: dict) -> str:
    if not m["localised"]:
        return "-"
    return f"{m['localisation_mean']:.1f} / {m['localisation_median']:.0f} / {m['localisation_within_8']:.2f}"
