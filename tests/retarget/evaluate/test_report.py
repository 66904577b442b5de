"""eval.md from a hand-made document."""

from __future__ import annotations

from dataclasses import asdict

from retarget.evaluate import ALIGNMENTS, METRICS, EvalConfig, markdown_report, report_notes


def _document() -> dict:
    scores = {align: {m: 0.5 for m in METRICS} | {m + "_se": 0.1 for m in METRICS} for align in ALIGNMENTS}
    real = {"amplitude": 0.9, "amplitude_per_joint": {}, "wrist_rise_pct": 12.0, "driver_wrist_rise_pct": 20.0,
            "proportion_error_pct": 3.0}  # fmt: skip
    doc = {
        "config": asdict(EvalConfig(pairs=3)),
        "methods": {
            "ours": {"kind": "network", "description": "our network", "weights": "w.pt"},
            "3D naive copy": {"kind": "3D reference", "description": "A unchanged"},
        },
        "results": {"val split": {"ours": scores, "3D naive copy": scores}},
        "real_pairs": {"a -> b": {"ours": real}},
        "silhouettes": {"ours": {"motion": 0.25, "view": -0.5}},
        "silhouette_errors": {"ours": {"motion": 0.01, "view": 0.02}},
        "remarks": ["a remark"],
    }
    doc["notes"] = report_notes(doc)
    return doc


def test_tables_silhouettes_and_notes() -> None:
    doc = _document()
    table = markdown_report(doc)
    assert "## val split: 3 cases of 64 frames" in table
    assert "| ours | 0.50 ± 0.10 | 0.5 | 0.500 | 0.500 | 0.50 | 0.50 ± 0.10 | 0.500 | 0.50 | 0.500 |" in table
    assert "| a -> b | ours | 0.90 | 12.0 (20.0) | 3.0 |" in table
    assert "| ours | 0.250 ± 0.010 | – | -0.500 ± 0.020 |" in table  # a network without a skeleton encoder
    assert "mean ± standard error over 10 such grids" in table
    del doc["silhouette_errors"]  # an eval.json written before the grids: one value each
    assert "| ours | 0.250 | – | -0.500 |" in markdown_report(doc)
    assert "- ours: our network; weights w.pt." in table
    assert "- 3D naive copy: A unchanged." in table and "- a remark" in table
    assert table.endswith("\n")


def test_notes_say_which_views_the_cases_take() -> None:
    doc = _document()
    assert "seen by camera B (13 view bins, pitch uniform in ±10°)" in report_notes(doc)[0]
    doc["config"] = asdict(EvalConfig(pairs=3, max_yaw=45, max_pitch=0))
    assert "(the view bins within ±45° of the front, pitch uniform in ±0°)" in report_notes(doc)[0]
    del doc["config"]["max_yaw"]  # an eval.json written before the option: all 13 bins
    assert "13 view bins" in report_notes(doc)[0]


def test_sections_without_real_tracks_or_networks() -> None:
    doc = _document() | {"real_pairs": {}, "silhouettes": {}}
    doc["notes"] = report_notes(doc)
    table = markdown_report(doc)
    assert "Real tracks" not in table and "silhouette" not in table.lower()
