"""`clone search index / query / eval` through typer's CliRunner, on tiny tracks built in tmp_path."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from clone.cli.main import app
from pose_io.writers import write_track
from tests.figures import walking_figure


def invoke(*args: str):
    return CliRunner().invoke(app, ["search", *args])


def one_error_line(result) -> str:
    assert result.exit_code == 2, result.output
    lines = [line for line in result.output.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), result.output
    return lines[0]


@pytest.fixture(scope="module")
def collection(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Three walkers unlike each other (stride, build, drift) in nested folders, and a query cut from one."""
    root = tmp_path_factory.mktemp("search")
    people = {
        "a/slow.npz": walking_figure(120, period=40.0, height=300.0, seed=1),
        "a/b/quick": walking_figure(120, period=18.0, height=260.0, arms=0.45, drift=10.0, seed=2),
        "wide.csv": walking_figure(120, period=28.0, height=380.0, shoulders=0.3, drift=150.0, seed=3),
    }
    for rel, track in people.items():
        write_track(track, root / "tracks" / rel)
    write_track(people["a/b/quick"].frames(24, 88), root / "query.npz")
    return root


def test_index_then_query(collection, tmp_path):
    index = tmp_path / "walkers.index"
    result = invoke("index", str(collection / "tracks"), "--out", str(index), "--device", "cpu")
    assert result.exit_code == 0, result.output
    assert f"wrote {index} (3 tracks, 360 frames)" in result.output
    assert index.is_file()

    result = invoke("query", str(collection / "query.npz"), "--index", str(index), "--top", "2", "--json",
                    "--device", "cpu")  # fmt: skip
    assert result.exit_code == 0, result.output
    doc = json.loads(result.output)
    assert doc["frames"] == 64 and len(doc["hits"]) == 2
    best = doc["hits"][0]
    assert Path(best["path"]).name == "quick" and best["score"] > 0.9
    # The walk repeats every 18 frames: any repetition of the cut is a right answer; the end stays in the track.
    assert min((best["start"] - 24) % 18, -(best["start"] - 24) % 18) <= 2
    assert best["end"] == min(120, best["start"] + 64)
    assert {"path", "track", "start", "end", "score"} == set(best)

    result = invoke("query", str(collection / "query.npz"), "--index", str(index), "--device", "cpu")
    assert result.exit_code == 0, result.output
    for column in ("rank", "track", "start", "end", "score"):
        assert column in result.output
    assert "quick" in result.output.split("\n", 4)[-1]


def test_user_errors_are_one_line(collection, tmp_path):
    index = tmp_path / "idx"
    index.write_text("not an index")
    assert "already exists" in one_error_line(invoke("index", str(collection / "tracks"), "--out", str(index)))
    assert "not a readable search index" in one_error_line(
        invoke("query", str(collection / "query.npz"), "--index", str(index), "--device", "cpu"))
    assert "no such search index" in one_error_line(
        invoke("query", str(collection / "query.npz"), "--index", str(tmp_path / "none"), "--device", "cpu"))
    assert "no such file" in one_error_line(invoke("index", str(tmp_path / "missing"), "--out", str(tmp_path / "o")))
    one_error_line(invoke("query", str(collection / "query.npz"), "--index", str(index), "--top", "0"))
    assert "device" in one_error_line(
        invoke("index", str(collection / "tracks"), "--out", str(tmp_path / "o"), "--device", "tpu"))
    assert not (tmp_path / "o").exists()


def test_a_short_query_is_an_error(collection, tmp_path):
    index = tmp_path / "walkers.index"
    assert invoke("index", str(collection / "tracks"), "--out", str(index), "--device", "cpu").exit_code == 0
    write_track(walking_figure(10), tmp_path / "short.npz")
    assert "at least" in one_error_line(
        invoke("query", str(tmp_path / "short.npz"), "--index", str(index), "--device", "cpu"))


def test_eval_on_a_tiny_world(tmp_path):
    from tests.retarget.world.humanoid import write_clip

    (tmp_path / "mocap" / "bandai").mkdir(parents=True)
    for name in ("walk_normal_001", "bow_normal_001", "run_normal_001", "walk_fast_001"):
        write_clip(tmp_path / "mocap" / "bandai" / f"dataset-1_{name}.bvh.gz")
    out = tmp_path / "eval.json"
    result = invoke("eval", "--mocap", str(tmp_path / "mocap"), "--cache", str(tmp_path / "cache"), "--queries", "3",
                    "--out", str(out), "--device", "cpu")  # fmt: skip
    assert result.exit_code == 0, result.output
    assert "motion codes (ours)" in result.output and "raw joints" in result.output
    assert ">= 45 degrees of yaw away" in result.output  # the default gap
    doc = json.loads(out.read_text())
    assert doc["queries"] == 3 and set(doc["methods"]) == {"motion", "joints"}
    assert doc["config"]["min_view_gap"] == 45.0 and doc["motion_over_joints"]["top1"] > 0

    mocap, cache = ["--mocap", str(tmp_path / "mocap")], ["--cache", str(tmp_path / "cache")]
    result = invoke("eval", *mocap, *cache, "--queries", "2", "--min-view-gap", "0", "--device", "cpu")
    assert result.exit_code == 0, result.output
    assert ">= 0 degrees of yaw away (0 draws redrawn)" in result.output
    assert "180" in one_error_line(invoke("eval", *mocap, *cache, "--min-view-gap", "200"))
    # Each view is indexed once per clip: no query keeps two candidates 180 degrees away.
    assert "use a smaller --min-view-gap" in one_error_line(
        invoke("eval", *mocap, *cache, "--min-view-gap", "180", "--device", "cpu"))
