"""Finding pose tracks in the files and folders a user names: the one folder walk every command uses.

    found = find_tracks(["clips/", "extra/walk.npz"], recursive=True)   # [FoundTrack(path, named), ...]

A named file or OpenPose folder (a folder of ``*_keypoints.json`` frames) is one track. Any other named folder
is searched for pose files (:data:`TRACK_SUFFIXES`) and OpenPose folders, in sorted order, hidden files and
folders skipped; ``recursive`` also searches its sub-folders (an OpenPose folder is never walked into). A
track reached twice (named, and inside a named folder) is kept once, at its first place, unless
``duplicates="refuse"`` makes that an error (for commands that write one output per input).
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

from pose_io.errors import InputError

#: Pose files a folder of tracks may hold (an OpenPose folder is one track too).
TRACK_SUFFIXES = (".npz", ".npy", ".csv", ".json")


@dataclass(frozen=True)
class FoundTrack:
    """One track: where it is, and whether the user named it (a named track that cannot be read is an error;
    one found inside a folder may be skipped)."""

    path: Path
    named: bool


def is_openpose_folder(path: Path) -> bool:
    """A folder holding ``*_keypoints.json`` frames: one track."""
    return path.is_dir() and any(path.glob("*_keypoints.json"))


def find_tracks(
    inputs: Iterable[str | os.PathLike],
    *,
    recursive: bool,
    duplicates: Literal["merge", "refuse"] = "merge",
) -> list[FoundTrack]:
    """The tracks the inputs name, in order (see the module docstring).

    Args:
        inputs: files and folders.
        recursive: search the sub-folders of a named folder too.
        duplicates: ``merge``: a track reached twice is listed once (named if either was); ``refuse``: an error.

    Raises:
        InputError: a path that does not exist, a named folder without tracks, or (``refuse``) a track named twice.
    """
    found: dict[Path, FoundTrack] = {}

    def add(path: Path, named: bool) -> None:
        key = path.resolve()
        first = found.get(key)
        if first is not None and duplicates == "refuse":
            raise InputError(f"{path}: named twice (also as {first.path})")
        found[key] = FoundTrack(path if first is None else first.path, named or (first is not None and first.named))

    for item in map(Path, inputs):
        if not item.exists():
            raise InputError(f"{item}: no such file or folder")
        if item.is_file() or is_openpose_folder(item):
            add(item, True)
            continue
        inside = _walk(item, recursive)
        if not inside:
            raise InputError(f"{item}: no pose files ({', '.join(TRACK_SUFFIXES)}) or OpenPose folders in it")
        for path in inside:
            add(path, False)
    return list(found.values())


def _walk(folder: Path, recursive: bool) -> list[Path]:
    """Pose files and OpenPose folders in ``folder`` (and below it when ``recursive``), by name within each folder."""
    out: list[Path] = []
    for root, dirs, files in os.walk(folder):
        here = Path(root)
        dirs[:] = sorted(d for d in dirs if not d.startswith("."))
        tracks = [d for d in dirs if is_openpose_folder(here / d)]
        pose_files = [f for f in files if f.lower().endswith(TRACK_SUFFIXES) and not f.startswith(".")]
        out += sorted([here / d for d in tracks] + [here / f for f in pose_files])
        dirs[:] = [d for d in dirs if d not in tracks] if recursive else []  # an OpenPose folder is one track
    return out
