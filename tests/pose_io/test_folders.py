"""The one folder walk: `clone retarget apply DIR` (flat, duplicates refused) and `clone search index DIR`
(recursive, duplicates merged) find tracks by the same rules."""

from __future__ import annotations

from pathlib import Path

import pytest

from pose_io.errors import InputError
from pose_io.folders import FoundTrack, find_tracks, is_openpose_folder
from pose_io.writers import write_track
from tests.figures import walking_figure


@pytest.fixture
def collection(tmp_path) -> Path:
    """clips/: two files, an OpenPose folder, a sub-folder with one more file, hidden and foreign files."""
    root = tmp_path / "clips"
    write_track(walking_figure(8), root / "b.npz")
    write_track(walking_figure(8), root / "a.csv")
    write_track(walking_figure(8), root / "c_openpose")  # an OpenPose folder: one track, its frames not walked
    write_track(walking_figure(8), root / "deeper" / "d.npz")
    (root / ".hidden.npz").write_bytes(b"junk")
    (root / "notes.txt").write_text("not a pose file")
    return root


def names(found: list[FoundTrack], root: Path) -> list[str]:
    return [f.path.relative_to(root).as_posix() for f in found]


def test_a_flat_walk_takes_files_and_openpose_folders_by_name(collection):
    found = find_tracks([collection], recursive=False)
    assert names(found, collection) == ["a.csv", "b.npz", "c_openpose"]
    assert not any(f.named for f in found) and is_openpose_folder(collection / "c_openpose")


def test_a_recursive_walk_goes_into_sub_folders_but_not_into_an_openpose_folder(collection):
    found = find_tracks([collection], recursive=True)
    assert names(found, collection) == ["a.csv", "b.npz", "c_openpose", "deeper/d.npz"]


def test_a_named_track_is_one_track_and_counts_as_named(collection):
    found = find_tracks([collection / "c_openpose", collection / "b.npz"], recursive=True)
    assert names(found, collection) == ["c_openpose", "b.npz"] and all(f.named for f in found)


def test_a_track_reached_twice_is_merged_or_refused(collection):
    merged = find_tracks([collection / "b.npz", collection], recursive=False)
    assert names(merged, collection) == ["b.npz", "a.csv", "c_openpose"] and merged[0].named
    with pytest.raises(InputError, match="named twice"):
        find_tracks([collection, collection / "b.npz"], recursive=False, duplicates="refuse")


def test_missing_paths_and_empty_folders_are_errors(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        find_tracks([tmp_path / "missing"], recursive=True)
    (tmp_path / "empty").mkdir()
    with pytest.raises(InputError, match="no pose files"):
        find_tracks([tmp_path / "empty"], recursive=True)
