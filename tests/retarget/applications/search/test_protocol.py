"""The retrieval evaluation's protocol: candidates at least ``min_view_gap`` of yaw away, and gap 0 = the old one."""

from __future__ import annotations

import json

import numpy as np
import pytest

from pose_io.errors import InputError
from retarget.applications.search.protocol import (
    MIN_OWN_CANDIDATES,
    RetrievalEvalConfig,
    candidate_mask,
    clip_windows,
    sample_entries,
    sample_queries,
    yaw_gap,
)

FPS = 30.0


@pytest.fixture(scope="module")
def split(tiny_world):
    """The test split of the package's tiny motion world."""
    return tiny_world.split("test")


def _draw(split, config: RetrievalEvalConfig):
    rng = np.random.default_rng(config.seed)
    entries = sample_entries(split, config, rng)
    queries, thrown = sample_queries(split, config, entries, rng, FPS)
    return entries, queries, thrown


def test_yaw_gap():
    assert yaw_gap(-90.0, 90.0) == 180.0 and yaw_gap(15.0, -30.0) == 45.0
    assert yaw_gap(170.0, -170.0) == pytest.approx(20.0)  # around the circle
    assert np.allclose(yaw_gap(np.array([0.0, 60.0, -45.0]), 15.0), [15.0, 45.0, 60.0])


@pytest.mark.parametrize(("gap", "seed"), [(45.0, 0), (45.0, 4), (75.0, 2)])
def test_every_candidate_is_at_least_the_gap_away(split, gap, seed):
    config = RetrievalEvalConfig(queries=40, min_view_gap=gap, seed=seed)
    entries, queries, thrown = _draw(split, config)
    assert len(queries) == 40
    characters = np.array([e.character for e in entries])
    views = np.array([e.view for e in entries])
    gaps_seen = []
    for q in queries:
        mask = candidate_mask(characters, views, q.character, q.view, split.views, gap)
        # Exactly the entries of another character whose view is at least `gap` degrees of yaw away.
        expected = [e.character != q.character and abs(split.views[e.view] - split.views[q.view]) >= gap
                    for e in entries]  # fmt: skip
        assert mask.tolist() == expected
        own = [e for e, m in zip(entries, mask) if m and e.clip == q.clip]
        assert len(own) >= MIN_OWN_CANDIDATES
        gaps_seen += [abs(split.views[e.view] - split.views[q.view]) for e, m in zip(entries, mask) if m]
    assert min(gaps_seen) >= gap
    # The gap is binding here: a plain draw would often keep a closer view, so some draws were thrown away.
    assert thrown > 0


def _old_protocol_queries(split, config: RetrievalEvalConfig) -> list[tuple[int, int, int, int, np.ndarray]]:
    """The queries as drawn before min_view_gap existed: no draw thrown away, one generator in the same order."""
    rng = np.random.default_rng(config.seed)
    sample_entries(split, config, rng)
    starts = clip_windows(split)
    clip_of = {split.window_labels[w].path: k for k, w in enumerate(starts)}
    eligible = [m for m, label in enumerate(split.window_labels) if label.clip_frames >= config.length]
    out = []
    for m in rng.choice(eligible, config.queries):
        label = split.window_labels[m]
        first = int(rng.integers(0, label.clip_frames - config.length + 1))
        character, view = int(rng.integers(split.num_characters)), int(rng.integers(split.num_views))
        joints = split.window(int(m), character, view, config.length, first - label.start, rng)
        out.append((clip_of[label.path], first, character, view, joints))
    return out


def test_gap_zero_is_the_old_protocol(split):
    config = RetrievalEvalConfig(queries=30, min_view_gap=0.0, seed=1)
    entries, queries, thrown = _draw(split, config)
    assert thrown == 0  # 4 performances per clip: at most one shares the character, one the view
    old = _old_protocol_queries(split, config)
    characters = np.array([e.character for e in entries])
    views = np.array([e.view for e in entries])
    for q, (clip, first, character, view, joints) in zip(queries, old, strict=True):
        assert (q.clip, q.first, q.character, q.view) == (clip, first, character, view)
        assert np.array_equal(q.track.joints, joints)
        old_candidates = (characters != q.character) & (views != q.view)
        mask = candidate_mask(characters, views, q.character, q.view, split.views, 0.0)
        assert np.array_equal(mask, old_candidates)
    # A gap of one view bin (15 degrees) asks the same as "another view bin".
    assert all(np.array_equal(candidate_mask(characters, views, q.character, q.view, split.views, 15.0),
                              candidate_mask(characters, views, q.character, q.view, split.views, 0.0))
               for q in queries)  # fmt: skip


def test_a_gap_no_query_can_keep_is_an_input_error(split):
    # 180 degrees: only -90 against +90, and a clip holds each view once, so no query keeps two candidates.
    with pytest.raises(InputError, match="use a smaller --min-view-gap"):
        _draw(split, RetrievalEvalConfig(queries=2, min_view_gap=180.0))
    for bad in (-1.0, 181.0):
        with pytest.raises(ValueError, match="min_view_gap"):
            RetrievalEvalConfig(min_view_gap=bad)


def test_evaluation_reports_the_gap(split):
    from retarget.api import load_retargeter
    from retarget.applications.search import MotionCodeEncoder
    from retarget.applications.search.evaluate import evaluate_retrieval, markdown_table, summary

    encoder = MotionCodeEncoder(load_retargeter(None, "cpu"))
    doc = evaluate_retrieval(split, encoder, RetrievalEvalConfig(queries=3, min_view_gap=60.0, seed=2), fps=FPS)
    assert doc["config"]["min_view_gap"] == 60.0 and doc["redrawn"] >= 0
    for m in doc["methods"].values():
        # The nearest candidate of a query's motion is never closer than the gap.
        assert m["queries_by_view_gap"]["0-30"] == m["queries_by_view_gap"]["30-60"] == 0
        assert m["top1_by_view_gap"]["0-30"] is None  # JSON null, not NaN
        assert sum(m["queries_by_view_gap"].values()) == 3
    ratios = doc["motion_over_joints"]
    joints = doc["methods"]["joints"]
    if joints["top1"] > 0:
        assert ratios["top1"] == pytest.approx(doc["methods"]["motion"]["top1"] / joints["top1"])
    else:
        assert ratios["top1"] is None
    json.dumps(doc, allow_nan=False)  # strict JSON: no NaN or Infinity left in the document
    table = markdown_table(doc)
    assert "0-30°" not in table and "30-60°" not in table  # columns no query falls in are left out
    assert ">= 60 degrees of yaw away" in summary(doc) and "top-1" in summary(doc).splitlines()[1]
    # A method that localises nothing: its localisation is None in the document and "-" in the table.
    lost = {"localised": 0, "localisation_mean": None, "localisation_median": None, "localisation_within_8": None}
    doc["methods"]["joints"] |= lost
    assert "| - (n=0) |" in markdown_table(doc)
