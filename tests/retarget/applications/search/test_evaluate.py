"""retarget.applications.search.evaluate: the retrieval evaluation's plumbing on a tiny motion world."""

from __future__ import annotations

import pytest


def test_retrieval_evaluation_on_a_tiny_world(encoder, tiny_world):
    from retarget.applications.search.evaluate import RetrievalEvalConfig, evaluate_retrieval, markdown_table

    split = tiny_world.split("test")
    calls = []
    config = RetrievalEvalConfig(queries=4, seed=3)
    doc = evaluate_retrieval(split, encoder, config, fps=tiny_world.config.fps,
                             progress=lambda done, total: calls.append((done, total)))  # fmt: skip
    assert calls[-1] == (8, 8)  # both methods
    assert doc["queries"] == 4 and doc["tracks"] == doc["clips"] * 4 and doc["split"] == "test"
    assert set(doc["methods"]) == {"motion", "joints"}
    for m in doc["methods"].values():
        assert 0.0 <= m["top1"] <= m["topk"] <= 1.0
        assert m["localised"] <= 4 and sum(m["queries_by_view_gap"].values()) == 4
    # One clip in the test split: every hit is the query's motion, and the same seed gives the same numbers.
    if doc["clips"] == 1:
        assert doc["methods"]["motion"]["top1"] == 1.0
    again = evaluate_retrieval(split, encoder, config, fps=tiny_world.config.fps)["methods"]
    for name, m in doc["methods"].items():
        assert {k: v for k, v in again[name].items() if k != "seconds_per_query"} == {
            k: v for k, v in m.items() if k != "seconds_per_query"}
    table = markdown_table(doc)
    assert "motion codes (ours)" in table and "raw joints" in table and "top-5" in table
    with pytest.raises(ValueError):
        RetrievalEvalConfig(pairs_per_clip=2)
