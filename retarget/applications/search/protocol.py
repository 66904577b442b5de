"""What the retrieval evaluation asks: the indexed performances, the queries and each query's candidates.

Every choice comes from one seeded generator (see :mod:`retarget.applications.search.evaluate` for the scoring):

- Index: every clip of the split, whole, performed by ``pairs_per_clip`` of the split's characters, each seen
  from its own view bin (characters and views distinct within a clip; pitch uniform in +-``MAX_PITCH``).
- Query: ``length`` frames of a random window of the split (at a random start inside its clip, so not on the
  8-frame code grid) performed by a random character A seen from a random view V.
- Candidates: the index entries of another character, from another view bin whose yaw is at least
  ``min_view_gap`` degrees from V's (:func:`candidate_mask`). A view bin's yaw is relative to the average facing
  of what it films (the query's window, the entry's whole clip), as everywhere in the motion world.
- Every query keeps at least ``MIN_OWN_CANDIDATES`` candidates of its own clip: a draw (window, start,
  character, view) that would keep fewer is thrown away and drawn again, whole, from the same generator, so
  the queries are uniform over the draws that keep enough. With ``min_view_gap`` 0 and ``pairs_per_clip`` >= 4
  no draw is ever thrown away (at most one entry of a clip shares A, at most one shares V), and the queries
  and candidates are those of the protocol before ``min_view_gap`` existed.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from itertools import product

import numpy as np

from pose_io.errors import InputError
from pose_io.track import PoseTrack
from retarget.inference.tracks import body15_track
from retarget.world import WorldSplit

#: Candidates of its own clip every query keeps (so that its own clip can always be found and localised).
MIN_OWN_CANDIDATES = 2

#: Draws tried per query before the protocol gives up (only a gap that almost no draw can meet gets near it).
MAX_DRAWS_PER_QUERY = 1000


@dataclass(frozen=True)
class RetrievalEvalConfig:
    """What the retrieval evaluation measures.

    Attributes:
        queries: number of queries.
        length: frames per query.
        pairs_per_clip: (character, view) performances of every clip in the index.
        top_k: hits looked at for the top-k accuracy.
        min_view_gap: degrees of yaw between the query's view and every candidate's (0: any other view bin).
            45 by default: the issue's "from another view", "from whichever side it is filmed"; with 0 most
            queries have a candidate of their motion 15 degrees away, where raw joints work too.
        phase_step: frames between the query phases of the pass over the whole index (None: automatic, see
            :mod:`retarget.applications.search.query`).
        seed: seed of every choice.
    """

    queries: int = 500
    length: int = 64
    pairs_per_clip: int = 4
    top_k: int = 5
    min_view_gap: float = 45.0
    phase_step: int | None = None
    seed: int = 0

    def __post_init__(self) -> None:
        if self.queries < 1 or self.length < 16 or self.pairs_per_clip < 3 or self.top_k < 1:
            raise ValueError("need queries >= 1, length >= 16, pairs_per_clip >= 3 and top_k >= 1")
        if not 0.0 <= self.min_view_gap <= 180.0:
            raise ValueError(f"min_view_gap must be in [0, 180] degrees, got {self.min_view_gap}")


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


def yaw_gap(a: np.ndarray | float, b: np.ndarray | float) -> np.ndarray:
    """Degrees between yaws ``a`` and ``b`` around the circle, in [0, 180] (broadcasts)."""
    return np.abs((np.asarray(a, dtype=np.float64) - b + 180.0) % 360.0 - 180.0)


def candidate_mask(
    characters: np.ndarray, views: np.ndarray, character: int, view: int, yaw_of: Sequence[float], min_view_gap: float
) -> np.ndarray:
    """Which entries a query may hit: another character, another view bin, at least ``min_view_gap`` of yaw away.

    Args:
        characters: [N] character of every entry.
        views: [N] view bin of every entry.
        character: the query's character.
        view: the query's view bin.
        yaw_of: yaw (degrees) of every view bin.
        min_view_gap: degrees.

    Returns:
        [N] bool.
    """
    yaws = np.asarray(yaw_of, dtype=np.float64)
    far = yaw_gap(yaws[views], yaws[view]) >= min_view_gap
    return (characters != character) & (views != view) & far


def clip_windows(split: WorldSplit) -> list[int]:
    """The window that starts each clip of ``split`` (window index per clip, in clip order)."""
    first: dict[str, int] = {}
    for w, label in enumerate(split.window_labels):
        if label.start == 0 and label.path not in first:
            first[label.path] = w
    return list(first.values())


def pose_track(joints: np.ndarray, split: WorldSplit, fps: float) -> PoseTrack:
    """[F, 15, 2] body15 pixels of ``split`` as a pose track."""
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
    split: WorldSplit, config: RetrievalEvalConfig, entries: list[Entry], rng: np.random.Generator, fps: float
) -> tuple[list[Query], int]:
    """Random windows of the split, at random starts, on random characters from random views.

    Args:
        split: the motion-world split.
        config: the protocol's numbers.
        entries: the indexed performances (:func:`sample_entries`): every query keeps ``MIN_OWN_CANDIDATES``
            candidates of its own clip among them (see the module's docstring).
        rng: the protocol's generator.
        fps: the world's frame rate.

    Returns:
        The queries, and how many draws were thrown away.

    Raises:
        InputError: no query fits the split (too short, or no draw keeps enough candidates at this gap).
    """
    starts = clip_windows(split)
    clip_of = {split.window_labels[w].path: k for k, w in enumerate(starts)}
    eligible = [m for m, label in enumerate(split.window_labels) if label.clip_frames >= config.length]
    if not eligible:
        raise InputError(f"{split.name} split: no clip has {config.length} frames for a query; use a shorter --length")
    characters = np.array([e.character for e in entries], dtype=np.int64)
    views = np.array([e.view for e in entries], dtype=np.int64)
    clips = np.array([e.clip for e in entries], dtype=np.int64)

    def keeps_enough(clip: int, character: int, view: int) -> bool:
        own = clips == clip
        mask = candidate_mask(characters[own], views[own], character, view, split.views, config.min_view_gap)
        return int(mask.sum()) >= MIN_OWN_CANDIDATES

    usable = sorted({clip_of[split.window_labels[m].path] for m in eligible})
    if not any(keeps_enough(*draw) for draw in product(usable, range(split.num_characters), range(split.num_views))):
        raise InputError(f"{split.name} split: no query keeps {MIN_OWN_CANDIDATES} performances of its clip at least "
                         f"{config.min_view_gap:g} degrees away; use a smaller --min-view-gap")  # fmt: skip
    out, thrown = [], 0
    for drawn in rng.choice(eligible, config.queries):
        m = int(drawn)
        for _ in range(MAX_DRAWS_PER_QUERY):
            label = split.window_labels[m]
            first = int(rng.integers(0, label.clip_frames - config.length + 1))
            character, view = int(rng.integers(split.num_characters)), int(rng.integers(split.num_views))
            if keeps_enough(clip_of[label.path], character, view):
                break
            thrown += 1
            m = int(rng.choice(eligible))  # the whole draw again: window, start, character and view
        else:
            raise InputError(f"{split.name} split: {MAX_DRAWS_PER_QUERY} draws in a row kept fewer than "
                             f"{MIN_OWN_CANDIDATES} candidates of their clip; use a smaller --min-view-gap")  # fmt: skip
        joints = split.window(m, character, view, config.length, first - label.start, rng)  # [L, 15, 2]
        out.append(Query(clip_of[label.path], label.group, first, character, view, pose_track(joints, split, fps)))
    return out, thrown
