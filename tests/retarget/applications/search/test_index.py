"""retarget.applications.search.index: finding tracks, building the index, its one file and the errors of bad ones."""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np
import pytest
import torch

from pose_io.errors import InputError
from pose_io.folders import find_tracks
from pose_io.track import PoseTrack
from pose_io.writers import write_track
from retarget.applications.search import build_index, load_index, save_index, search
from tests.figures import walking_figure
from tests.retarget.applications.search.moving import FRAMES


def _write_collection(root: Path, tracks: list[PoseTrack]) -> None:
    write_track(tracks[0], root / "a" / "first.npz")
    write_track(tracks[1], root / "a" / "b" / "second")  # an OpenPose folder: one track, its frames not walked
    write_track(tracks[2], root / "third.csv")
    (root / "a" / "notes.json").write_text("{}")  # found in a folder, unreadable: skipped
    (root / "a" / ".hidden.npz").write_bytes(b"junk")  # hidden: not even looked at


def test_index_round_trip(encoder, tracks, tmp_path):
    _write_collection(tmp_path / "tracks", tracks)
    found = find_tracks([tmp_path / "tracks"], recursive=True)  # what build_index walks
    names = sorted(f.path.name for f in found)
    assert names == ["first.npz", "notes.json", "second", "third.csv"]
    assert not any(f.named for f in found)
    again = find_tracks([tmp_path / "tracks" / "third.csv", tmp_path / "tracks"], recursive=True)  # listed once
    assert (again[0].path.name, again[0].named) == ("third.csv", True) and len(again) == 4
    calls = []
    index, skipped = build_index([tmp_path / "tracks"], encoder, progress=lambda d, t, p: calls.append((d, t)))
    assert [Path(s.path).name for s in skipped] == ["notes.json"]
    assert calls[-1] == (4, 4)
    assert sorted(Path(p).name for p in index.paths) == ["first.npz", "second", "third.csv"]
    assert list(index.frames) == [FRAMES] * 3 and list(index.track_fps) == [30.0] * 3

    path = save_index(index, tmp_path / "collection.index")
    assert path.is_file() and not list(tmp_path.glob(".collection*"))  # one file, no temporary left
    with pytest.raises(InputError, match="already exists"):
        save_index(index, path)
    loaded = load_index(path)
    assert loaded.paths == index.paths and (loaded.kind, loaded.digest, loaded.stride) == ("motion", encoder.digest, 8)
    assert np.array_equal(loaded.offsets, index.offsets) and np.array_equal(loaded.frames, index.frames)
    assert torch.allclose(loaded.features, index.features, atol=2e-2, rtol=1e-3)  # float16 on disk
    query = tracks[1].frames(16, 80)
    a, b = search(index, encoder, query, top_k=3), search(loaded, encoder, query, top_k=3)
    assert [(h.path, h.start, h.end) for h in a] == [(h.path, h.start, h.end) for h in b]
    assert [h.score for h in a] == pytest.approx([h.score for h in b], abs=1e-3)


def test_a_named_unreadable_track_is_an_error(encoder, tmp_path):
    (tmp_path / "bad.json").write_text("[1, 2")
    with pytest.raises(InputError, match="bad.json"):
        build_index([tmp_path / "bad.json"], encoder)
    with pytest.raises(InputError, match="no such file"):
        build_index([tmp_path / "missing"], encoder)
    with pytest.raises(InputError, match="no readable pose tracks"):
        build_index([tmp_path], encoder)  # only the unreadable one, found in a folder
    write_track(walking_figure(10), tmp_path / "short.npz")
    with pytest.raises(InputError, match="at least 16"):
        build_index([tmp_path / "short.npz"], encoder)


def _rewrite(path: Path, out: Path, **changes: object) -> Path:
    with np.load(path, allow_pickle=False) as data:
        arrays = {k: data[k] for k in data.files}
    arrays.update(changes)
    for key in [k for k, v in changes.items() if v is None]:
        del arrays[key]
    with open(out, "wb") as f:
        np.savez(f, **arrays)
    return out


def test_bad_index_files_are_input_errors(encoder, index, tmp_path):
    good = save_index(index, tmp_path / "good.npz")
    cases = {
        "missing": (tmp_path / "nope.npz", "no such search index"),
        "text": (tmp_path / "text.npz", "not a readable search index"),
        "truncated": (tmp_path / "cut.npz", "not a readable search index"),
        "other npz": (tmp_path / "other.npz", "not a clone2d search index"),
        "newer": (_rewrite(good, tmp_path / "newer.npz", version=np.array(99)), "version 99; this clone2d reads up"),
        "no features": (_rewrite(good, tmp_path / "nofeat.npz", features=None), "damaged search index"),
        "bad offsets": (_rewrite(good, tmp_path / "offsets.npz", offsets=np.array([0, 5, 3, 60, 80])), "damaged"),
        "nan": (_rewrite(good, tmp_path / "nan.npz", features=np.full((128, 80), np.nan, np.float16)), "damaged"),
    }
    (tmp_path / "text.npz").write_text("hello")
    (tmp_path / "cut.npz").write_bytes(good.read_bytes()[:500])
    np.savez(tmp_path / "other.npz", joints=np.zeros((3, 15, 2)))
    for name, (path, message) in cases.items():
        with pytest.raises(InputError, match=message):
            load_index(path)
        assert name  # for the failure report
    assert zipfile.is_zipfile(good)
