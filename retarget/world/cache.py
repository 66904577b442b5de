"""The motion worlds in a cache folder: what each holds and costs on disk, and removing the least recently used.

Every distinct set of world settings (characters, their spread, seed, frame rate, window) is a folder of its own
(``world-<key>``, :mod:`retarget.world.dataset`), a few GB with hundreds of extra characters, and nothing deleted
them. ``MotionWorld.build`` marks a folder used (``pose_io.atomic.mark_used``) when it opens it from the cache, so the worlds a user still trains
on stay and old experiments go first.
"""

from __future__ import annotations

import json
import logging
import re
import shutil
import time
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pose_io.errors import InputError
from retarget.world.config import default_cache_dir

log = logging.getLogger(__name__)

_WORLD_NAME = re.compile(r"world-[0-9a-f]{16}")
# Temp folders of builds that never finished (``pose_io.atomic.atomic_dir``: ``.world-<key>.<random>.tmp``).
_TEMP_NAME = re.compile(r"\.world-[0-9a-f]{16}\..+\.tmp")
# A temp folder younger than this may be a build still running in another process: it is left alone.
UNFINISHED_AGE_S = 24 * 3600.0


@dataclass(frozen=True)
class CachedWorld:
    """One folder of a world cache.

    Attributes:
        path: the folder.
        bytes: its size on disk (sum of its files).
        last_used: POSIX time it was last built or opened from the cache.
        config: its settings as stored (``WorldConfig`` as a dict; empty for an unfinished build).
        finished: False for the temp folder of a build that never finished.
    """

    path: Path
    bytes: int
    last_used: float
    config: dict[str, Any]
    finished: bool = True


def _folder_bytes(folder: Path) -> int:
    total = 0
    for file in folder.rglob("*"):
        try:
            if file.is_file() and not file.is_symlink():
                total += file.stat().st_size
        except OSError:  # deleted meanwhile
            continue
    return total


def cached_worlds(cache_dir: str | Path | None = None) -> list[CachedWorld]:
    """The worlds in ``cache_dir`` (default ``~/.cache/clone2d/world``), most recently used first, then the
    unfinished builds; other files and folders there are not listed.

    Raises:
        InputError: ``cache_dir`` is not a folder (a missing default cache is simply empty).
    """
    folder = Path(cache_dir) if cache_dir is not None else default_cache_dir()
    if not folder.is_dir():
        if cache_dir is None and not folder.exists():
            return []
        raise InputError(f"{folder}: no such cache folder")
    worlds = []
    for entry in folder.iterdir():
        finished = bool(_WORLD_NAME.fullmatch(entry.name))
        if not (finished or _TEMP_NAME.fullmatch(entry.name)) or not entry.is_dir() or entry.is_symlink():
            continue
        config: dict[str, Any] = {}
        if finished:
            try:
                config = dict(json.loads((entry / "meta.json").read_text())["config"])
            except (OSError, ValueError, KeyError, TypeError):
                finished = False  # no readable meta.json: a world that would be rebuilt anyway
        try:
            used = entry.stat().st_mtime
        except OSError:
            continue
        worlds.append(CachedWorld(entry, _folder_bytes(entry), used, config, finished))
    return sorted(worlds, key=lambda w: (not w.finished, -w.last_used))


def stale_worlds(worlds: Iterable[CachedWorld], keep: int, now: float | None = None) -> list[CachedWorld]:
    """What a cleaning removes: every finished world but the ``keep`` most recently used, and every unfinished
    build older than ``UNFINISHED_AGE_S`` (younger ones may still be running)."""
    if keep < 0:
        raise ValueError(f"keep must be >= 0, got {keep}")
    now = time.time() if now is None else now
    finished = sorted((w for w in worlds if w.finished), key=lambda w: -w.last_used)
    unfinished = [w for w in worlds if not w.finished and now - w.last_used > UNFINISHED_AGE_S]
    return finished[keep:] + unfinished


def remove_worlds(worlds: Iterable[CachedWorld]) -> int:
    """Delete the folders; returns the bytes freed. A folder that is already gone is skipped."""
    freed = 0
    for world in worlds:
        try:
            shutil.rmtree(world.path)
        except FileNotFoundError:
            continue
        freed += world.bytes
        log.info("removed %s (%.1f GB)", world.path, world.bytes / 1e9)
    return freed


__all__ = ["UNFINISHED_AGE_S", "CachedWorld", "cached_worlds", "remove_worlds", "stale_worlds"]
