"""pose_io.atomic: outputs appear whole or not at all, and nothing the user had is replaced unasked."""

from __future__ import annotations

import os
import stat

import pytest

from pose_io import InputError
from pose_io.atomic import atomic_dir, atomic_file, check_new_output


def _mode(path) -> int:
    return stat.S_IMODE(os.stat(path).st_mode)


def _leftovers(folder):
    return sorted(p.name for p in folder.iterdir() if p.name.startswith("."))


def test_atomic_file_appears_on_success(tmp_path):
    path = tmp_path / "sub" / "out.json"
    with atomic_file(path) as tmp:
        assert tmp.parent == path.parent and tmp.suffix == ".json" and not path.exists()
        tmp.write_text("done")
    assert path.read_text() == "done"
    assert _leftovers(path.parent) == []


def test_atomic_file_gets_plain_open_permissions(tmp_path):
    with atomic_file(tmp_path / "a.txt") as tmp:
        tmp.write_text("x")
    (tmp_path / "b.txt").write_text("x")
    assert _mode(tmp_path / "a.txt") == _mode(tmp_path / "b.txt")  # not mkstemp's private 0600


def test_a_failure_leaves_nothing_and_keeps_the_old_file(tmp_path):
    path = tmp_path / "out.txt"
    path.write_text("old")
    with pytest.raises(RuntimeError, match="boom"), atomic_file(path) as tmp:
        tmp.write_text("half")
        raise RuntimeError("boom")
    assert path.read_text() == "old"
    assert _leftovers(tmp_path) == []


def test_existing_output_is_kept_unless_overwrite(tmp_path):
    path = tmp_path / "out.txt"
    path.write_text("mine")
    with (
        pytest.raises(InputError, match="out.txt: already exists; choose another --out or pass --overwrite"),
        atomic_file(path, overwrite=False),
    ):
        raise AssertionError("not reached")
    assert path.read_text() == "mine"
    with atomic_file(path, overwrite=True) as tmp:
        tmp.write_text("new")
    assert path.read_text() == "new"


def test_check_new_output(tmp_path):
    check_new_output(tmp_path / "free")
    check_new_output(tmp_path, overwrite=True)
    with pytest.raises(InputError, match="already exists"):
        check_new_output(tmp_path)


def test_atomic_dir_appears_whole(tmp_path):
    path = tmp_path / "poses"
    with atomic_dir(path) as tmp:
        (tmp / "a.json").write_text("1")
        assert not path.exists()
    assert sorted(p.name for p in path.iterdir()) == ["a.json"]
    assert _leftovers(tmp_path) == []


def test_atomic_dir_replaces_only_after_the_new_content_is_complete(tmp_path):
    path = tmp_path / "poses"
    path.mkdir()
    (path / "old.json").write_text("old")
    with pytest.raises(InputError, match="already exists"), atomic_dir(path):
        raise AssertionError("not reached")
    with pytest.raises(RuntimeError), atomic_dir(path, overwrite=True) as tmp:
        (tmp / "new.json").write_text("new")
        raise RuntimeError("failed half way")
    assert sorted(p.name for p in path.iterdir()) == ["old.json"]  # the old content survives a failure
    with atomic_dir(path, overwrite=True) as tmp:
        (tmp / "new.json").write_text("new")
    assert sorted(p.name for p in path.iterdir()) == ["new.json"]
    assert _leftovers(tmp_path) == []


def test_atomic_dir_may_replace_a_file(tmp_path):
    path = tmp_path / "out"
    path.write_text("a file")
    with atomic_dir(path, overwrite=True) as tmp:
        (tmp / "x").write_text("1")
    assert path.is_dir() and (path / "x").read_text() == "1"
    assert _leftovers(tmp_path) == []


def test_folders_get_plain_mkdir_permissions_and_the_umask_is_left_alone(tmp_path, monkeypatch):
    def no_umask(mask: int) -> int:
        raise AssertionError("library code must not set the process umask (other threads create files)")

    (tmp_path / "plain").mkdir()
    monkeypatch.setattr(os, "umask", no_umask)
    with atomic_dir(tmp_path / "made") as tmp:
        (tmp / "x").write_text("1")
    with atomic_file(tmp_path / "made.txt") as tmp:
        tmp.write_text("1")
    assert _mode(tmp_path / "made") == _mode(tmp_path / "plain")
