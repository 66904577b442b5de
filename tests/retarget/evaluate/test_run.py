"""`clone retarget eval` end to end: the folder it writes and its one-line input errors."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from typer.testing import CliRunner

from clone.cli.main import app
from retarget.evaluate import BASELINES, OFFICIAL_FILES, REFERENCES_3D
from retarget.inference.config import REFINE_STEPS
from tests.retarget.evaluate.helpers import TINY


def test_cli_writes_the_table_plots_and_json(
    shared_dir: Path, tiny_mocap: Path, cache: Path, tiny_weights: Path, tmp_path: Path
) -> None:
    out = tmp_path / "eval"
    args = ["retarget", "eval", "--mocap", str(tiny_mocap), "--cache", str(cache), "--weights", str(tiny_weights),
            "--compare", f"no triplet={tiny_weights}", "--bvh", str(tiny_mocap / Path(TINY[0]).name),
            "--official", str(shared_dir / "official_2dmr" / "weights"),
            "--pairs", "3", "--split", "val", "--threads", "1", "--device", "cpu", "--out", str(out),
            "--probe-steps", "3"]  # fmt: skip
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    doc = json.loads((out / "eval.json").read_text())
    rows = {"ours", "no triplet", *OFFICIAL_FILES, *BASELINES, *REFERENCES_3D}
    # The tiny world's walks never turn as captured: no captured-turn source.
    assert list(doc["results"]) == ["val split", "val split, turned 90-360°", "extra mocap (1 clip)"]
    for source in doc["results"].values():
        assert set(source) == rows
        for row in source.values():
            assert set(row) == {"pose", "with_root", "placed"}
            assert all(np.isfinite(v) for v in row["pose"].values())
            assert 0.0 <= row["placed"]["pck_0.1"] <= 1.0
    assert set(doc["silhouettes"]["ours"]) == {"motion", "body", "view"}
    assert all(-1.0 <= v <= 1.0 for v in doc["silhouettes"]["no triplet"].values())
    assert set(doc["silhouettes"]["authors' view-only"]) == {"motion", "view"}
    assert set(doc["silhouette_errors"]["authors' view-only"]) == {"motion", "view"}
    assert all(v > 0 for v in doc["silhouette_errors"]["ours"].values())  # ten grids that differ
    assert set(doc["silhouettes"]["proportion probe"]) == {"body"}  # scored as a skeleton code only
    assert sorted(p.name for p in out.glob("*.png")) == [
        "codes_authors_full.png", "codes_authors_skeleton_only.png", "codes_authors_view_only.png",
        "codes_no_triplet.png", "codes_ours.png",
    ]
    table = (out / "eval.md").read_text()
    assert "| ours |" in table and "| 3D rotation copy |" in table and "h² × 10⁻³" in table
    assert "| proportion probe | – |" in table and "trained for 3 steps" in table
    # ours and --compare rows refine motion codes as inference does; the authors' run as released
    assert doc["methods"]["ours"]["refine_steps"] == doc["methods"]["no triplet"]["refine_steps"] == str(REFINE_STEPS)
    assert doc["methods"]["authors' full"]["refine_steps"] == "0"
    assert f"motion codes refined by {REFINE_STEPS} steps" in table and "motion codes not refined" in table
    assert "| ours |" in result.output  # printed too
    again = CliRunner().invoke(app, args)
    assert again.exit_code == 2 and "already exists" in again.output


def test_cli_input_errors_are_one_line(tiny_mocap: Path, cache: Path, tiny_weights: Path, tmp_path: Path) -> None:
    base = ["retarget", "eval", "--mocap", str(tiny_mocap), "--cache", str(cache), "--weights", str(tiny_weights),
            "--pairs", "2", "--split", "val"]  # fmt: skip
    cases = {
        "expected NAME=PATH": ["--compare", "nopath"],
        "none of pretrained_full.pth": ["--official", str(tmp_path)],
        "that row name is taken": ["--compare", f"ours={tiny_weights}"],
        "valid: test, val": ["--split", "train"],
        "--refine-steps: must be >= 0": ["--refine-steps", "-2"],
    }
    for k, (message, extra) in enumerate(cases.items()):
        out = tmp_path / f"out{k}"
        result = CliRunner().invoke(app, [*base, *extra, "--out", str(out)])
        assert result.exit_code == 2, result.output
        assert message in result.output and "Traceback" not in result.output
        assert not out.exists()
