"""The motion world dataset: every mocap clip replayed on many characters, seen from 13 views.

``MotionWorld.build`` reads every BVH / AMC under a folder, maps them onto the canonical skeleton at one
frame rate, splits them into train / val / test by motion (takes of the same motion stay together) and
draws disjoint characters for each split (the named evaluation characters go to test). It stores the 3D
joint positions of every (character, clip) pair once; 2D views are projected on the fly, which is cheap.

Cache: ``<cache_dir>/world-<key>/`` where the key hashes the settings, the file list (paths and sizes)
and ``WORLD_VERSION``. The folder holds ``meta.json`` and plain ``.npy`` arrays, opened memory-mapped,
so a second ``build`` is fast and data-loader workers share pages instead of copying them.

The settings are ``config.WorldConfig``, the building ``build``, a split's windows ``split.WorldSplit``.
"""

from __future__ import annotations

import hashlib
import json
import logging
import time
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path

from pose_io.atomic import atomic_dir, mark_used
from pose_io.errors import InputError
from retarget.world.build import find_mocap_files, write_world
from retarget.world.camera import CANVAS_SIZE
from retarget.world.config import SPLITS, WORLD_VERSION, WorldConfig, default_cache_dir
from retarget.world.split import WorldSplit

log = logging.getLogger(__name__)


def _cache_key(cfg: WorldConfig, files: list[tuple[str, int]]) -> str:
    config = asdict(cfg)
    if not cfg.extra_train_characters:  # settings added later enter the key only when used: old caches stay valid
        del config["extra_train_characters"], config["extra_spread"]
    blob = json.dumps({"version": WORLD_VERSION, "config": config, "files": files}, sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


class MotionWorld:
    """A built (cached) motion world; get one with ``MotionWorld.build`` or ``MotionWorld.open``."""

    def __init__(self, folder: Path) -> None:
        self.folder = Path(folder)
        meta_path = self.folder / "meta.json"
        try:
            self.meta = json.loads(meta_path.read_text())
        except FileNotFoundError:
            raise InputError(f"{self.folder}: not a motion world cache (no meta.json)") from None
        except json.JSONDecodeError:
            raise InputError(f"{meta_path}: broken motion world metadata") from None
        if self.meta.get("version") != WORLD_VERSION:
            raise InputError(
                f"{self.folder}: motion world version {self.meta.get('version')} (this code reads {WORLD_VERSION});"
                " rebuild it"
            )
        cfg = dict(self.meta["config"])
        cfg["canvas_size"] = tuple(cfg["canvas_size"])
        self.config = WorldConfig(**cfg)
        self._splits: dict[str, WorldSplit] = {}

    @classmethod
    def open(cls, folder: str | Path) -> MotionWorld:
        """Open a cache folder written by ``build``."""
        return cls(Path(folder))

    @classmethod
    def build(
        cls,
        mocap_dir: str | Path,
        cache_dir: str | Path | None = None,
        seed: int = 0,
        fps: float = 30.0,
        n_train_characters: int = 64,
        n_val_characters: int = 8,
        n_test_characters: int = 8,
        window: int = 64,
        stride: int = 32,
        val_fraction: float = 0.1,
        test_fraction: float = 0.1,
        canvas_size: tuple[int, int] = CANVAS_SIZE,
        extra_train_characters: int = 0,
        extra_spread: float = 1.0,
        rebuild: bool = False,
        progress: Callable[[int, int, str], None] | None = None,
    ) -> MotionWorld:
        """Build the world from every mocap file under ``mocap_dir``, or open it from the cache.

        Args:
            mocap_dir: folder searched recursively for ``.bvh``, ``.bvh.gz`` and ``.amc`` (with ASF).
            cache_dir: where worlds are cached (default ``default_cache_dir()``).
            seed, fps, n_*_characters, window, stride, val_fraction, test_fraction, canvas_size,
                extra_train_characters, extra_spread: see ``WorldConfig``.
            rebuild: build again even when the cache has this world.
            progress: called as ``progress(done, total, what)`` while files load.

        Returns:
            The world.

        Raises:
            InputError: no mocap files, none usable, or too few motions for the three splits.
        """
        cfg = WorldConfig(
            seed=seed, fps=float(fps), window=window, stride=stride, n_train_characters=n_train_characters,
            n_val_characters=n_val_characters, n_test_characters=n_test_characters, val_fraction=val_fraction,
            test_fraction=test_fraction, canvas_size=(int(canvas_size[0]), int(canvas_size[1])),
            extra_train_characters=extra_train_characters, extra_spread=float(extra_spread),
        )
        mocap_dir = Path(mocap_dir)
        if not mocap_dir.is_dir():
            raise InputError(f"{mocap_dir}: no such folder")
        files = find_mocap_files(mocap_dir)
        if not files:
            raise InputError(f"{mocap_dir}: no .bvh, .bvh.gz or .amc files")
        listing = [(p.relative_to(mocap_dir).as_posix(), p.stat().st_size) for p in files]
        cache_root = Path(cache_dir) if cache_dir is not None else default_cache_dir()
        folder = cache_root / f"world-{_cache_key(cfg, listing)}"
        if folder.is_dir() and not rebuild:
            try:
                world = cls(folder)
                log.info("motion world from cache %s", folder)
                mark_used(folder)  # `clone world clean` removes the least recently used first
                return world
            except InputError as exc:
                log.warning("%s; rebuilding", exc)
                rebuild = True
        started = time.perf_counter()
        try:
            with atomic_dir(folder, overwrite=rebuild or folder.exists()) as tmp:
                write_world(tmp, mocap_dir, files, cfg, progress, started)
        except OSError:
            # Another process finished the same world first: use it.
            if not (folder / "meta.json").is_file():
                raise
        return cls(folder)

    @property
    def path(self) -> Path:
        return self.folder

    def split(self, name: str) -> WorldSplit:
        """The ``"train"``, ``"val"`` or ``"test"`` split."""
        if name not in SPLITS:
            raise ValueError(f"unknown split {name!r}; valid: {', '.join(SPLITS)}")
        if name not in self._splits:
            self._splits[name] = WorldSplit(name, self.folder, self.meta, self.config)
        return self._splits[name]

    def summary(self) -> dict:
        """Counts per split (clips, motions, frames, windows, characters, views, bytes) and sources."""
        out = json.loads(json.dumps(self.meta["summary"]))
        out["cache"] = str(self.folder)
        return out


__all__ = ["MotionWorld"]
