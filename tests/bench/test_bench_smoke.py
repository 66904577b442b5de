"""bench.run: one cheap stage end to end into tmp_path, the structure of what it writes, and stage selection.

No test here asserts a timing value: times depend on the machine and its load. What is checked is that the
results have the documented structure and that the stored ratios are the ones the stored numbers give.
"""

from __future__ import annotations

import json
import sys
import types

import pytest
import torch

from bench import run as bench_run
from bench.harness import row
from bench.run import SCHEMA_VERSION, STAGES, main, select

ROW_KEYS = {"case", "variant", "value", "unit", "baseline", "baseline_variant", "speedup", "load_average", "extra"}
MACHINE_KEYS = {"machine", "cpus_available", "python", "torch", "torch_threads", "date", "cpu_model", "cpu_flags"}
STAGE_KEYS = {"rows", "notes", "seconds", "load_average_before", "load_average_after", "date", "quick"}


@pytest.fixture(autouse=True)
def _restore_threads():
    """``main`` sets torch to one thread for the whole process; give the other tests theirs back."""
    threads = torch.get_num_threads()
    yield
    torch.set_num_threads(threads)


@pytest.fixture
def fake_stage(monkeypatch):
    """Register a stage ``fake`` whose rows are fixed numbers: ``module.result`` is what it returns."""
    module = types.ModuleType("bench_fake_stage")
    module.result = {"rows": [], "notes": []}
    module.calls = []

    def run(quick: bool = False, repeats: int | None = None, **_: object) -> dict:
        module.calls.append((quick, repeats))
        if isinstance(module.result, Exception):
            raise module.result
        return dict(module.result)

    module.run = run
    monkeypatch.setitem(sys.modules, "bench_fake_stage", module)
    monkeypatch.setattr(bench_run, "STAGES", {**STAGES, "fake": ("bench_fake_stage", False)})
    return module


def _results(folder):
    return json.loads((folder / "results.json").read_text()), (folder / "results.md").read_text()


def test_quick_draw_run_writes_the_documented_structure(tmp_path):
    assert main(["--only", "draw", "--quick", "--repeats", "1", "--out", str(tmp_path)]) == 0
    doc, md = _results(tmp_path)
    assert doc["schema_version"] == SCHEMA_VERSION
    machine = doc["machine"]
    assert MACHINE_KEYS <= set(machine)
    assert machine["torch"] == torch.__version__
    assert machine["torch_threads"] == 1  # main runs every stage on one thread
    assert isinstance(machine["cpus_available"], int) and machine["cpus_available"] >= 1
    assert set(machine["cpu_flags"]) <= {"avx2", "fma", "avx512f", "avx512_bf16", "avx512_vnni", "amx_bf16"}
    assert list(doc["stages"]) == ["draw"]
    stage = doc["stages"]["draw"]
    assert STAGE_KEYS <= set(stage) and "error" not in stage
    assert stage["quick"] is True
    assert len(stage["rows"]) == 3
    for r in stage["rows"]:
        assert ROW_KEYS <= set(r)
        assert r["unit"] == "frames/s" and r["case"] == "512x512, body15"
        assert r["baseline_variant"] == "per-limb cv2.line + cv2.circle, integer coords, LINE_8"
        assert r["value"] > 0 and r["baseline"] > 0
        # The ratio is ours / baseline (a rate: higher is better), rounded as documented.
        assert r["speedup"] == round(r["value"] / r["baseline"], 3)
    # Every row of the stage is compared with the one baseline measured in the same run.
    assert len({r["baseline"] for r in stage["rows"]}) == 1
    assert [r["variant"] for r in stage["rows"]] == [
        "draw_pose (anti-aliased, default)", "draw_pose(antialias=False)", "canvas clear only"]
    # The markdown names the machine and has one table line per row.
    assert "## draw" in md and machine["torch"] in md and "(--quick)" in md
    for r in stage["rows"]:
        assert sum(line.startswith(f"| {r['case']} | {r['variant']} |") for line in md.splitlines()) == 1


def test_stored_speedups_follow_the_stored_numbers(tmp_path, fake_stage):
    fake_stage.result = {"rows": [
        row("case", "ours", 300.0, "frames/s", 100.0, "plain"),
        row("case", "ours", 0.5, "s", 2.0, "plain", higher_is_better=False, share=0.25),
        row("case", "no baseline", 7.0, "MiB"),
    ], "notes": ["a note"]}
    assert main(["--only", "fake", "--repeats", "4", "--out", str(tmp_path)]) == 0
    assert fake_stage.calls == [(False, 4)]
    doc, md = _results(tmp_path)
    rows = doc["stages"]["fake"]["rows"]
    assert [r["speedup"] for r in rows] == [3.0, 4.0, None]
    assert rows[1]["extra"] == {"share": 0.25}
    assert doc["stages"]["fake"]["quick"] is False and "(--quick)" not in md
    assert "| case | ours | 300 | frames/s | 100 (plain) | 3 |" in md
    assert "| case | no baseline | 7 | MiB |  |  |" in md
    assert "- a note" in md


def test_a_failing_stage_is_recorded_and_the_run_fails(tmp_path, fake_stage):
    fake_stage.result = RuntimeError("no GPU here")
    assert main(["--only", "fake,draw", "--quick", "--repeats", "1", "--out", str(tmp_path)]) == 1
    doc, md = _results(tmp_path)
    assert list(doc["stages"]) == ["draw", "fake"]  # registry order; the failure did not stop draw
    failed = doc["stages"]["fake"]
    assert failed["rows"] == [] and failed["error"] == "RuntimeError: no GPU here"
    assert "RuntimeError" in failed["traceback"]
    assert "**failed**: `RuntimeError: no GPU here`" in md
    assert "error" not in doc["stages"]["draw"]


def test_only_merges_with_earlier_stages(tmp_path, fake_stage):
    (tmp_path / "results.json").write_text(json.dumps(
        {"schema_version": SCHEMA_VERSION, "machine": {}, "load_average": [], "stages": {"gpu": {"rows": []}}}))
    assert main(["--only", "fake", "--out", str(tmp_path)]) == 0
    assert list(_results(tmp_path)[0]["stages"]) == ["gpu", "fake"]


def test_results_of_another_schema_are_not_merged(tmp_path, fake_stage):
    (tmp_path / "results.json").write_text(json.dumps(
        {"schema_version": SCHEMA_VERSION + 1, "machine": {}, "load_average": [], "stages": {"gpu": {"rows": []}}}))
    assert main(["--only", "fake", "--out", str(tmp_path)]) == 0
    assert list(_results(tmp_path)[0]["stages"]) == ["fake"]
    (tmp_path / "results.json").write_text("{not json")
    assert main(["--only", "fake", "--out", str(tmp_path)]) == 0
    assert list(_results(tmp_path)[0]["stages"]) == ["fake"]


def test_unknown_stage_is_refused_before_anything_runs(tmp_path, capsys):
    with pytest.raises(SystemExit) as info:
        main(["--only", "draw,nope", "--out", str(tmp_path / "out")])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert "unknown stage(s) nope" in err and "valid: " + ", ".join(STAGES) in err
    assert not (tmp_path / "out").exists()


def test_stage_selection():
    assert select(None) == [n for n, (_, default) in STAGES.items() if default]
    assert "train_quality" not in select(None) and "draw" in select(None)
    assert select("gpu, draw,") == ["draw", "gpu"]  # registry order, blanks ignored
    assert select("train_quality") == ["train_quality"]  # opt-in stages run when named
    with pytest.raises(ValueError, match="unknown stage\\(s\\) nope, zzz; valid: " + ", ".join(STAGES)):
        select("nope,draw,zzz")


def test_real_stage_budgets():
    from bench.real import budgets

    assert budgets(False, None) == [3.0] and budgets(True, None) == [1.0]
    assert budgets(False, "1,3,10") == [1.0, 3.0, 10.0] and budgets(False, 2.5) == [2.5]
    for bad in ("0", "", "1,-2", "900"):
        with pytest.raises(ValueError, match="budgets"):
            budgets(False, bad)


def test_real_stage_starts():
    from bench.real import chosen_starts

    assert chosen_starts(None) == ["prior", "none"] and chosen_starts("prior") == ["prior"]
    assert chosen_starts("none, prior,none") == ["none", "prior"]
    for bad in ("", "random", "prior,x"):
        with pytest.raises(ValueError, match="starts"):
            chosen_starts(bad)


def test_stage_options_reach_the_stage(fake_stage):
    seen = {}

    def stage(**kwargs):
        seen.update(kwargs)
        return {"rows": []}

    fake_stage.run = stage
    bench_run.run_stage("fake", quick=True, repeats=None, minutes="1,10", strips=None, starts="prior")
    assert seen["minutes"] == "1,10" and "strips" not in seen and seen["quick"] is True
    assert seen["starts"] == "prior"
