"""bench: the draw stage end to end into tmp_path, and the schema of what it writes (no timing asserts)."""

from __future__ import annotations

import json

import pytest

from bench.run import SCHEMA_VERSION, STAGES, main, select

ROW_KEYS = {"case", "variant", "value", "unit", "baseline_variant", "baseline", "speedup", "load_average", "extra"}


def test_draw_stage_writes_results(tmp_path):
    assert main(["--only", "draw", "--quick", "--repeats", "1", "--out", str(tmp_path)]) == 0
    doc = json.loads((tmp_path / "results.json").read_text())
    assert doc["schema_version"] == SCHEMA_VERSION
    assert {"torch", "date", "cpus_available", "torch_threads"} <= set(doc["machine"])
    assert list(doc["stages"]) == ["draw"]
    stage = doc["stages"]["draw"]
    assert "error" not in stage
    assert len(stage["load_average_before"]) == 3 and stage["seconds"] >= 0
    assert len(stage["rows"]) >= 2
    for r in stage["rows"]:
        assert ROW_KEYS <= set(r)
        assert r["unit"] == "frames/s" and r["value"] > 0 and r["baseline"] > 0
        assert r["speedup"] == pytest.approx(r["value"] / r["baseline"], rel=1e-2)
    md = (tmp_path / "results.md").read_text()
    assert "## draw" in md and "draw_pose" in md and doc["machine"]["torch"] in md


def test_only_merges_with_earlier_stages(tmp_path):
    (tmp_path / "results.json").write_text(json.dumps(
        {"schema_version": SCHEMA_VERSION, "machine": {}, "load_average": [], "stages": {"gpu": {"rows": []}}}))
    assert main(["--only", "draw", "--quick", "--repeats", "1", "--out", str(tmp_path)]) == 0
    assert set(json.loads((tmp_path / "results.json").read_text())["stages"]) == {"draw", "gpu"}


def test_stage_selection():
    assert "train_quality" not in select(None) and "draw" in select(None)
    assert select("gpu,draw") == ["draw", "gpu"]  # registry order
    with pytest.raises(ValueError, match="valid: " + ", ".join(STAGES)):
        select("nope")
