"""retarget.world.cache and `clone world list / clean`: the cached worlds, most recently used first; cleaning
keeps the newest and never touches anything else in the folder."""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest
from typer.testing import CliRunner

from clone.cli.main import app
from pose_io.errors import InputError
from retarget.world import MotionWorld
from retarget.world.cache import UNFINISHED_AGE_S, cached_worlds, remove_worlds, stale_worlds
from tests.retarget.world.test_dataset import SMALL, tiny_mocap  # noqa: F401 - the fixture

HOUR = 3600.0


def _age(path: Path, hours: float) -> None:
    stamp = time.time() - hours * HOUR
    os.utime(path, (stamp, stamp))


@pytest.fixture()
def cache(tiny_mocap: Path, tmp_path: Path) -> Path:  # noqa: F811 - the fixture imported above
    """Two finished worlds (seed 0 used an hour ago, seed 1 three hours ago), an old unfinished build, a recent
    one, and a file of the user's."""
    root = tmp_path / "cache"
    for seed, hours in ((0, 1), (1, 3)):
        _age(MotionWorld.build(tiny_mocap, root, seed=seed, **SMALL).path, hours)
    for name, hours in ((".world-0123456789abcdef.x1.tmp", 30), (".world-0123456789abcdef.x2.tmp", 1)):
        (root / name).mkdir()
        (root / name / "train_positions.npy").write_bytes(bytes(1000))
        _age(root / name, hours)
    (root / "notes.txt").write_text("mine")
    return root


def test_worlds_are_listed_most_recently_used_first(cache: Path, tiny_mocap: Path) -> None:  # noqa: F811
    worlds = cached_worlds(cache)
    assert [w.finished for w in worlds] == [True, True, False, False]
    assert [w.config["seed"] for w in worlds[:2]] == [0, 1]
    assert all(w.bytes > 0 for w in worlds)
    assert worlds[0].bytes == sum(f.stat().st_size for f in worlds[0].path.iterdir())
    MotionWorld.build(tiny_mocap, cache, seed=1, **SMALL)  # opened from the cache: now the most recent
    assert [w.config["seed"] for w in cached_worlds(cache)[:2]] == [1, 0]


def test_cleaning_keeps_the_newest_and_young_unfinished_builds(cache: Path) -> None:
    worlds = cached_worlds(cache)
    stale = stale_worlds(worlds, keep=1)
    assert [w.path.name for w in stale] == [worlds[1].path.name, ".world-0123456789abcdef.x1.tmp"]
    assert stale_worlds(worlds, keep=2, now=time.time() + UNFINISHED_AGE_S) == worlds[2:]  # both old by then
    assert remove_worlds(stale) == sum(w.bytes for w in stale)
    left = sorted(p.name for p in cache.iterdir())
    assert left == sorted([worlds[0].path.name, ".world-0123456789abcdef.x2.tmp", "notes.txt"])
    assert remove_worlds(stale) == 0  # already gone
    with pytest.raises(ValueError, match="keep"):
        stale_worlds(worlds, keep=-1)


def test_a_missing_cache_folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("HOME", str(tmp_path))  # the default cache does not exist yet: nothing cached
    assert cached_worlds() == []
    with pytest.raises(InputError, match="no such cache folder"):
        cached_worlds(tmp_path / "nowhere")


def test_world_list_and_clean_commands(cache: Path) -> None:
    runner = CliRunner()
    newest, older = (w.path for w in cached_worlds(cache)[:2])
    listed = runner.invoke(app, ["world", "list", "--cache", str(cache)])
    assert listed.exit_code == 0, listed.output
    lines = listed.output.splitlines()
    assert lines[0].startswith(newest.name) and "characters 3 / 2 / 2, seed 0" in lines[0]
    assert "unfinished build" in lines[2] and lines[-1].startswith("4 world(s)")
    dry = runner.invoke(app, ["world", "clean", "--cache", str(cache), "--dry-run"])
    assert dry.exit_code == 0 and f"would remove {older}" in dry.output and older.is_dir()
    done = runner.invoke(app, ["world", "clean", "--cache", str(cache)])
    assert done.exit_code == 0 and "freed" in done.output and "(2 world(s))" in done.output
    assert newest.is_dir() and not older.exists() and (cache / "notes.txt").read_text() == "mine"
    none = runner.invoke(app, ["world", "clean", "--cache", str(cache), "--keep", "0"])
    assert none.exit_code == 0 and not newest.exists() and (cache / "notes.txt").exists()
