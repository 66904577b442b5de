"""The motion world dataset: every mocap clip replayed on many characters, seen from 13 views.

``MotionWorld.build`` reads every BVH / AMC under a folder, maps them onto the canonical skeleton at one
frame rate, splits them into train / val / test by motion (takes of the same motion stay together) and
draws disjoint characters for each split (the named evaluation characters go to test). It stores the 3D
joint positions of every (character, clip) pair once; 2D views are projected on the fly, which is cheap.

Cache: ``<cache_dir>/world-<key>/`` where the key hashes the settings, the file list (paths and sizes)
and ``WORLD_VERSION``. The folder holds ``meta.json`` and plain ``.npy`` arrays, opened memory-mapped,
so a second ``build`` is fast and data-loader workers share pages instead of copying them.

Labels: a sample is (motion, character, view) where motion is a window index (64 frames, stride 32),
character an index into the split's characters and view an index into ``VIEW_YAWS``.
"""

from __future__ import annotations

import hashlib
import json
import logging
import re
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np

from pose_io.atomic import atomic_dir, check_free_space
from pose_io.errors import InputError
from pose_io.layouts import BODY15
from retarget.windows import strided_starts as window_starts  # this module's name for it
from retarget.world.camera import (
    AIM_HEIGHT,
    CANVAS_SIZE,
    MAX_PITCH,
    VIEW_YAWS,
    WORLD_CAMERAS,
    Camera,
    CameraSpread,
    facing_angles,
    frame_camera,
    perspective_xy,
    view_rotations,
)
from retarget.world.rigs import load_motion, motion_name
from retarget.world.skeleton import (
    BONE_NAMES,
    NAMED_CHARACTERS,
    WORLD_JOINTS,
    Motion3D,
    Skeleton,
    retarget_3d,
    sample_skeleton,
)

log = logging.getLogger(__name__)

# Bump when anything that changes the cached arrays changes (rig mapping, head points, sampling...).
WORLD_VERSION = 2
SPLITS: tuple[str, ...] = ("train", "val", "test")
_ROOT = WORLD_JOINTS.index("mid_hip")
_BODY15_IDX = np.array([WORLD_JOINTS.index(n) for n in BODY15.joints], dtype=np.int64)
_MOCAP_SUFFIXES = (".bvh", ".bvh.gz", ".amc")


def default_cache_dir() -> Path:
    """``~/.cache/clone2d/world``."""
    return Path.home() / ".cache" / "clone2d" / "world"


@dataclass(frozen=True)
class WorldConfig:
    """Settings of a motion world (all of them enter the cache key).

    Attributes:
        seed: seeds the split of motions and the characters.
        fps: frame rate every clip is resampled to.
        window: window length in frames.
        stride: step between window starts.
        n_train_characters, n_val_characters, n_test_characters: sampled characters per split (test
            also gets every ``NAMED_CHARACTERS`` entry).
        val_fraction, test_fraction: share of each source's frames held out (whole motions).
        canvas_size: (width, height) of the 2D views (framing rule of ``camera.frame_camera``).
        extra_train_characters: training characters beyond the sampled ones, drawn from a random stream of
            their own (val and test characters stay those of a world without them).
        extra_spread: factor on the proportion spread of the extra characters (``sample_skeleton``).
    """

    seed: int = 0
    fps: float = 30.0
    window: int = 64
    stride: int = 32
    n_train_characters: int = 64
    n_val_characters: int = 8
    n_test_characters: int = 8
    val_fraction: float = 0.1
    test_fraction: float = 0.1
    canvas_size: tuple[int, int] = CANVAS_SIZE
    extra_train_characters: int = 0
    extra_spread: float = 1.0

    def __post_init__(self) -> None:
        if self.window < 2 or self.stride < 1:
            raise InputError(f"window must be >= 2 and stride >= 1, got {self.window} and {self.stride}")
        if not self.fps > 0:
            raise InputError(f"fps must be positive, got {self.fps}")
        if min(self.n_train_characters, self.n_val_characters, self.n_test_characters) < 1:
            raise InputError("every split needs at least one character")
        if not (0 <= self.val_fraction < 0.5 and 0 <= self.test_fraction < 0.5):
            raise InputError("val_fraction and test_fraction must be in [0, 0.5)")
        if self.extra_train_characters < 0 or not 0 < self.extra_spread <= 4:
            raise InputError("extra_train_characters must be >= 0 and extra_spread in (0, 4]")


class WindowLabel(NamedTuple):
    """Where a window comes from."""

    clip: str  # clip name (file stem)
    path: str  # file path relative to the mocap folder
    start: int  # first frame in the clip (at the world's fps)
    group: str  # motion group: takes of one motion share it and always share a split
    clip_frames: int  # frames in the clip: valid offsets are -start .. clip_frames - start - length


def motion_group(rel_path: str) -> str:
    """Motion identity used to split: CMU ``01_01`` and ``001_01`` -> ``cmu:1_1``; else the name without
    its take number (``walk_normal_002`` -> ``walk_normal``)."""
    stem = motion_name(rel_path)
    m = re.fullmatch(r"0*(\d+)_0*(\d+)", stem)
    if m:
        return f"cmu:{int(m[1])}_{int(m[2])}"
    return re.sub(r"[_\-]\d+$", "", stem)


def find_mocap_files(mocap_dir: Path) -> list[Path]:
    """Every ``.bvh``, ``.bvh.gz`` and ``.amc`` under ``mocap_dir``, sorted by relative path."""
    files = [p for p in mocap_dir.rglob("*") if p.is_file() and p.name.lower().endswith(_MOCAP_SUFFIXES)]
    return sorted(files, key=lambda p: p.relative_to(mocap_dir).as_posix())


def _cache_key(cfg: WorldConfig, files: list[tuple[str, int]]) -> str:
    config = asdict(cfg)
    if not cfg.extra_train_characters:  # settings added later enter the key only when used: old caches stay valid
        del config["extra_train_characters"], config["extra_spread"]
    blob = json.dumps({"version": WORLD_VERSION, "config": config, "files": files}, sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


def assign_splits(
    groups: Sequence[str], sources: Sequence[str], frames: Sequence[int], cfg: WorldConfig
) -> list[str]:
    """Split name per clip: whole motion groups, stratified by source folder, by share of frames.

    Within each source the groups are shuffled (seeded) and handed to val until it holds
    ``val_fraction`` of the source's frames, then to test, the rest to train. A source with fewer than
    three groups goes to train entirely.
    """
    out = ["train"] * len(groups)
    rng = np.random.default_rng([cfg.seed, 1])
    for source in sorted(set(sources)):
        members = [i for i, s in enumerate(sources) if s == source]
        group_frames: dict[str, int] = {}
        for i in members:
            group_frames[groups[i]] = group_frames.get(groups[i], 0) + int(frames[i])
        names = sorted(group_frames)
        if len(names) < 3:
            continue
        total = sum(group_frames.values())
        held = {"val": 0, "test": 0}
        target = {"val": cfg.val_fraction * total, "test": cfg.test_fraction * total}
        chosen: dict[str, str] = {}
        for g in (names[k] for k in rng.permutation(len(names))):
            split = next((s for s in ("val", "test") if held[s] < target[s]), "train")
            chosen[g] = split
            if split != "train":
                held[split] += group_frames[g]
        if "train" not in chosen.values():  # tiny sources: keep one group for training
            chosen[names[-1]] = "train"
        for i in members:
            out[i] = chosen[groups[i]]
    return out


def make_characters(cfg: WorldConfig) -> dict[str, list[Skeleton]]:
    """Disjoint characters per split: sampled ones (seeded), plus the named ones in test."""
    rng = np.random.default_rng([cfg.seed, 2])
    counts = {"train": cfg.n_train_characters, "val": cfg.n_val_characters, "test": cfg.n_test_characters}
    out: dict[str, list[Skeleton]] = {}
    for split in SPLITS:
        out[split] = [
            Skeleton(sample_skeleton(rng).lengths, name=f"{split}_{k:03d}") for k in range(counts[split])
        ]
    out["test"] += list(NAMED_CHARACTERS.values())
    extra = np.random.default_rng([cfg.seed, 3])
    out["train"] += [
        Skeleton(sample_skeleton(extra, cfg.extra_spread).lengths, name=f"train_extra_{k:03d}")
        for k in range(cfg.extra_train_characters)
    ]
    return out


class WorldSplit:
    """One split of a motion world: windows x characters x views.

    Attributes:
        name: "train", "val" or "test".
        positions: [C, F, 18, 3] float32 (memory-mapped) every character's replay of every clip,
            clips concatenated along F.
        source_positions: [F, 18, 3] the clips on their own skeletons.
        characters: the C characters.
        window_length: the default window length.
        canvas_size: (width, height) of the 2D views.
    """

    def __init__(self, name: str, folder: Path, meta: dict, config: WorldConfig) -> None:
        self._args = (name, Path(folder), meta, config)
        self.name = name
        info = meta["splits"][name]
        self.positions = np.load(folder / f"{name}_positions.npy", mmap_mode="r")
        self.source_positions = np.load(folder / f"{name}_source.npy", mmap_mode="r")
        self._windows = np.load(folder / f"{name}_windows.npy")
        self._clip_offsets = np.asarray(info["clip_offsets"], dtype=np.int64)
        self._clip_frames = np.asarray(info["clip_frames"], dtype=np.int64)
        self.clips: tuple[dict, ...] = tuple(info["clips"])
        self.characters: tuple[Skeleton, ...] = tuple(
            Skeleton(tuple(c["lengths"]), c["name"]) for c in info["characters"]
        )
        self.window_length = config.window
        self.canvas_size = tuple(config.canvas_size)
        self.views: tuple[float, ...] = VIEW_YAWS
        self.window_labels: tuple[WindowLabel, ...] = tuple(
            WindowLabel(
                self.clips[c]["name"], self.clips[c]["path"], int(s), self.clips[c]["group"], int(self._clip_frames[c])
            )
            for c, s in self._windows
        )

    def __reduce__(self) -> tuple:
        # Pickle the folder, not the memory-mapped arrays: data-loader workers reopen the same files.
        return (WorldSplit, self._args)

    def __repr__(self) -> str:
        return (f"WorldSplit({self.name!r}, motions={self.num_motions}, characters={self.num_characters}, "
                f"views={self.num_views})")

    @property
    def num_motions(self) -> int:
        """Number of windows."""
        return int(self._windows.shape[0])

    @property
    def num_characters(self) -> int:
        return len(self.characters)

    @property
    def num_views(self) -> int:
        return len(self.views)

    @property
    def num_clips(self) -> int:
        return len(self.clips)

    @property
    def character_names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.characters)

    def _frames(self, motion: int, length: int, offset: int) -> slice:
        if not 0 <= motion < self.num_motions:
            raise IndexError(f"{self.name}: motion {motion} out of range 0..{self.num_motions - 1}")
        clip, start = (int(v) for v in self._windows[motion])
        first = start + offset
        if length < 1 or first < 0 or first + length > self._clip_frames[clip]:
            raise ValueError(
                f"{self.name}: frames {first}..{first + length - 1} are outside clip "
                f"{self.clips[clip]['name']} ({self._clip_frames[clip]} frames)"
            )
        base = int(self._clip_offsets[clip]) + first
        return slice(base, base + length)

    def window3d(self, motion: int, character: int, length: int | None = None, offset: int = 0) -> np.ndarray:
        """[length, 18, 3] float32 3D joints of a window on a character, metres, Y up, first root over
        the origin (x = z = 0) and the ground at y = 0.

        Args:
            motion: window index.
            character: character index.
            length: frames (default the world's window); ``offset + length`` must stay inside the clip.
            offset: frames after the window's start.
        """
        if not 0 <= character < self.num_characters:
            raise IndexError(f"{self.name}: character {character} out of range 0..{self.num_characters - 1}")
        frames = self._frames(motion, self.window_length if length is None else length, offset)
        pos = np.array(self.positions[character, frames], dtype=np.float32)
        pos[..., 0] -= pos[0, _ROOT, 0]
        pos[..., 2] -= pos[0, _ROOT, 2]
        return pos

    def camera(self, view: int, pitch_deg: float = 0.0) -> Camera:
        """The framing-rule camera of view bin ``view``."""
        if not 0 <= view < self.num_views:
            raise IndexError(f"view {view} out of range 0..{self.num_views - 1}")
        return frame_camera(self.views[view], pitch_deg, self.canvas_size)

    def window(
        self,
        motion: int,
        character: int,
        view: int,
        length: int | None = None,
        offset: int = 0,
        rng: np.random.Generator | None = None,
        pitch_deg: float | None = None,
        cameras: CameraSpread = WORLD_CAMERAS,
    ) -> np.ndarray:
        """[length, 15, 2] float32 body15 pixels (x right, y down) of a window on a character from a view.

        The view's yaw is relative to the window's average facing; the ground under the window's first
        root lands at (W/2, 0.9 H) (``camera.frame_camera``).

        Args:
            motion: window index.
            character: character index.
            view: view bin (index into ``views``).
            length: frames (default the world's window).
            offset: frames after the window's start.
            rng: draws the camera from ``cameras``; None: pitch 0.
            pitch_deg: an explicit pitch (overrides ``rng``).
            cameras: how ``rng`` draws the camera (default: the world's, pitch in +-``MAX_PITCH`` degrees).
        """
        pitch = None if pitch_deg is None else [pitch_deg]
        return self.windows([motion], [character], [view], length, rng, offset, pitch, cameras)[0]

    def windows(
        self,
        motions: Sequence[int],
        characters: Sequence[int],
        views: Sequence[int],
        length: int | None = None,
        rng: np.random.Generator | None = None,
        offset: int = 0,
        pitch_deg: Sequence[float] | None = None,
        cameras: CameraSpread = WORLD_CAMERAS,
    ) -> np.ndarray:
        """[B, length, 15, 2] float32: ``window`` for B (motion, character, view) triples at once.

        Args:
            motions, characters, views: [B] indices.
            length: frames (default the world's window).
            rng: draws each camera from ``cameras``; None: pitch 0.
            offset: frames after each window's start.
            pitch_deg: [B] explicit pitches (override ``rng``).
            cameras: how ``rng`` draws cameras (default: the world's, pitch in +-``MAX_PITCH``).
        """
        if not len(motions) == len(characters) == len(views):
            raise ValueError("motions, characters and views must have the same length")
        views_a = np.asarray(views, dtype=np.int64)
        if ((views_a < 0) | (views_a >= self.num_views)).any():
            raise IndexError(f"views must be in 0..{self.num_views - 1}")
        pos = np.stack([self.window3d(m, c, length, offset) for m, c in zip(motions, characters)])  # [B, L, 18, 3]
        return self.project(pos, views_a, rng, pitch_deg, cameras)

    def project(
        self,
        pos: np.ndarray,
        views: Sequence[int] | np.ndarray,
        rng: np.random.Generator | None = None,
        pitch_deg: Sequence[float] | None = None,
        cameras: CameraSpread = WORLD_CAMERAS,
    ) -> np.ndarray:
        """[B, L, 18, 3] world joints (as ``window3d`` gives them) -> [B, L, 15, 2] float32 body15 pixels.

        The camera and framing rule of ``windows``: each clip's yaw is relative to its own average facing,
        the ground under its first root lands at (W/2, 0.9 H).

        Args:
            pos: [B, L, 18, 3] metres, first root over the origin, ground at y = 0.
            views: [B] view bins.
            rng: draws each camera from ``cameras`` (pitch, and distance when it has perspective); None:
                pitch 0, weak perspective.
            pitch_deg: [B] explicit pitches (override ``rng``'s; weak perspective).
            cameras: how ``rng`` draws the cameras (default: the world's, pitch in +-``MAX_PITCH``).
        """
        b = len(pos)
        views_a = np.asarray(views, dtype=np.int64)
        distance = np.full(b, np.inf)
        if pitch_deg is not None:
            pitch = np.asarray(pitch_deg, dtype=np.float64).reshape(b)
        elif rng is not None:
            pitch, distance = cameras.draw(rng, b)
        else:
            pitch = np.zeros(b)
        yaw = np.asarray(self.views, dtype=np.float64)[views_a] + facing_angles(pos)
        rot = view_rotations(yaw, pitch)  # [B, 3, 3]
        pts = pos[:, :, _BODY15_IDX, None, :]  # [B, L, 15, 1, 3]
        if np.isfinite(distance).any():
            cam3 = (rot[:, None, None].astype(np.float32) * pts).sum(axis=-1)  # [B, L, 15, 3]
            aim = rot @ np.array([0.0, AIM_HEIGHT, 0.0])  # [B, 3]
            cam = perspective_xy(cam3, aim, distance).astype(np.float32)
        else:  # only camera x and y are needed
            cam = (rot[:, None, None, :2, :].astype(np.float32) * pts).sum(axis=-1)  # [B, L, 15, 2] metres, y up
        ref = frame_camera(0.0, 0.0, self.canvas_size)
        cam *= np.float32(ref.scale)
        cam[..., 0] += np.float32(ref.tx)
        cam[..., 1] = np.float32(ref.ty) - cam[..., 1]
        return cam


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
                return world
            except InputError as exc:
                log.warning("%s; rebuilding", exc)
                rebuild = True
        started = time.perf_counter()
        try:
            with atomic_dir(folder, overwrite=rebuild or folder.exists()) as tmp:
                _write_world(tmp, mocap_dir, files, cfg, progress, started)
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


def _check_space(out: Path, characters: dict[str, list[Skeleton]], split_of: Sequence[str], frames: list[int]) -> None:
    """Refuse before allocating when the disk cannot hold the positions (characters + source, per split)."""
    need = sum(
        (len(characters[split]) + 1) * sum(f for f, s in zip(frames, split_of) if s == split) * len(WORLD_JOINTS) * 12
        for split in SPLITS
    )
    check_free_space(out, need, "the motion world",
                     "choose a --cache folder on a bigger disk, or fewer --extra-characters")


def _write_world(
    out: Path,
    mocap_dir: Path,
    files: list[Path],
    cfg: WorldConfig,
    progress: Callable[[int, int, str], None] | None,
    started: float,
) -> None:
    motions: list[Motion3D] = []
    rels: list[str] = []
    skipped: list[dict[str, str]] = []
    for k, path in enumerate(files):
        rel = path.relative_to(mocap_dir).as_posix()
        if progress is not None:
            progress(k, len(files), rel)
        try:
            motion = load_motion(path, fps=cfg.fps)
        except InputError as exc:
            log.warning("skipping %s", exc)
            skipped.append({"path": rel, "reason": str(exc)})
            continue
        if motion.num_frames < cfg.window:
            skipped.append({"path": rel, "reason": f"{motion.num_frames} frames, shorter than a window"})
            continue
        motions.append(motion)
        rels.append(rel)
    if progress is not None:
        progress(len(files), len(files), "")
    if not motions:
        raise InputError(f"{mocap_dir}: no usable mocap clips ({len(skipped)} skipped)")

    groups = [motion_group(r) for r in rels]
    sources = [r.split("/", 1)[0] if "/" in r else "." for r in rels]
    frames = [m.num_frames for m in motions]
    split_of = assign_splits(groups, sources, frames, cfg)
    for split in SPLITS:
        if split not in split_of:
            raise InputError(
                f"{mocap_dir}: too few distinct motions for train/val/test ({len(set(groups))} motion groups)"
            )
    characters = make_characters(cfg)
    _check_space(out, characters, split_of, frames)

    summary: dict = {
        "version": WORLD_VERSION,
        "fps": cfg.fps,
        "window": cfg.window,
        "stride": cfg.stride,
        "views": len(VIEW_YAWS),
        "view_yaws": list(VIEW_YAWS),
        "pitch_range_deg": MAX_PITCH,
        "canvas_size": list(cfg.canvas_size),
        "files": len(files),
        "skipped": skipped,
        "sources": {},
        "splits": {},
    }
    for source in sorted(set(sources)):
        idx = [i for i, s in enumerate(sources) if s == source]
        summary["sources"][source] = {"clips": len(idx), "frames": int(sum(frames[i] for i in idx))}

    meta: dict = {"version": WORLD_VERSION, "config": asdict(cfg), "splits": {}}
    for split in SPLITS:
        idx = [i for i, s in enumerate(split_of) if s == split]
        clip_frames = [frames[i] for i in idx]
        offsets = np.concatenate([[0], np.cumsum(clip_frames)[:-1]]).astype(np.int64)
        total = int(sum(clip_frames))
        chars = characters[split]
        # [C, F, 18, 3] written straight into the cache file, one character at a time.
        pos = np.lib.format.open_memmap(
            out / f"{split}_positions.npy", mode="w+", dtype=np.float32, shape=(len(chars), total, len(WORLD_JOINTS), 3)
        )
        src = np.lib.format.open_memmap(
            out / f"{split}_source.npy", mode="w+", dtype=np.float32, shape=(total, len(WORLD_JOINTS), 3)
        )
        for k, i in enumerate(idx):
            src[offsets[k]: offsets[k] + frames[i]] = motions[i].positions
        for c, skel in enumerate(chars):
            for k, i in enumerate(idx):
                pos[c, offsets[k]: offsets[k] + frames[i]] = retarget_3d(motions[i], skel).positions
        pos.flush()
        src.flush()
        del pos, src
        windows = [(k, s) for k, i in enumerate(idx) for s in window_starts(frames[i], cfg.window, cfg.stride)]
        np.save(out / f"{split}_windows.npy", np.array(windows, dtype=np.int64).reshape(-1, 2))
        heights = [c.height for c in chars]
        meta["splits"][split] = {
            "clips": [
                {"name": motions[i].name, "path": rels[i], "group": groups[i], "source": sources[i], "frames": frames[i]}
                for i in idx
            ],
            "clip_offsets": offsets.tolist(),
            "clip_frames": clip_frames,
            "characters": [{"name": c.name, "lengths": list(c.lengths), "height": c.height} for c in chars],
            "bones": list(BONE_NAMES),
        }
        summary["splits"][split] = {
            "clips": len(idx),
            "motions": len({groups[i] for i in idx}),
            "frames": total,
            "windows": len(windows),
            "characters": len(chars),
            "views": len(VIEW_YAWS),
            "samples": len(windows) * len(chars) * len(VIEW_YAWS),
            "height_range_m": [round(min(heights), 3), round(max(heights), 3)],
            "positions_mb": round(len(chars) * total * len(WORLD_JOINTS) * 3 * 4 / 2**20, 1),
        }
    summary["build_seconds"] = round(time.perf_counter() - started, 1)
    meta["summary"] = summary
    (out / "meta.json").write_text(json.dumps(meta, indent=1))


__all__ = [
    "SPLITS",
    "WORLD_VERSION",
    "MotionWorld",
    "WindowLabel",
    "WorldConfig",
    "WorldSplit",
    "assign_splits",
    "default_cache_dir",
    "find_mocap_files",
    "make_characters",
    "motion_group",
    "window_starts",
]
