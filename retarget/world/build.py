"""Building a motion world from a mocap folder: which files, which split each motion goes to, which
characters each split gets, and the cached arrays (``write_world``)."""

from __future__ import annotations

import json
import logging
import re
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict
from pathlib import Path

import numpy as np

from pose_io.atomic import check_free_space
from pose_io.errors import InputError
from retarget.inference.windows import strided_starts
from retarget.world.camera import MAX_PITCH, VIEW_YAWS
from retarget.world.characters import NAMED_CHARACTERS, sample_skeleton
from retarget.world.config import SPLITS, WORLD_VERSION, WorldConfig
from retarget.world.rigs import load_motion, motion_name
from retarget.world.skeleton import (
    BONE_NAMES,
    WORLD_JOINTS,
    Motion3D,
    Skeleton,
    retarget_3d,
)

log = logging.getLogger(__name__)

_MOCAP_SUFFIXES = (".bvh", ".bvh.gz", ".amc")


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


def _check_space(out: Path, characters: dict[str, list[Skeleton]], split_of: Sequence[str], frames: list[int]) -> None:
    """Refuse before allocating when the disk cannot hold the positions (characters + source, per split)."""
    need = sum(
        (len(characters[split]) + 1) * sum(f for f, s in zip(frames, split_of) if s == split) * len(WORLD_JOINTS) * 12
        for split in SPLITS
    )
    check_free_space(out, need, "the motion world",
                     "choose a --cache folder on a bigger disk, or fewer --extra-characters")


def write_world(
    out: Path,
    mocap_dir: Path,
    files: list[Path],
    cfg: WorldConfig,
    progress: Callable[[int, int, str], None] | None,
    started: float,
) -> None:
    """Read the clips, split them, replay them on the characters and write the world's files into ``out``."""
    motions, rels, skipped = _read_clips(mocap_dir, files, cfg, progress)
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
        chars = characters[split]
        offsets, windows = _write_split(out, split, [motions[i] for i in idx], chars, cfg)
        clip_frames = [frames[i] for i in idx]
        total = int(sum(clip_frames))
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
            "windows": windows,
            "characters": len(chars),
            "views": len(VIEW_YAWS),
            "samples": windows * len(chars) * len(VIEW_YAWS),
            "height_range_m": [round(min(heights), 3), round(max(heights), 3)],
            "positions_mb": round(len(chars) * total * len(WORLD_JOINTS) * 3 * 4 / 2**20, 1),
        }
    summary["build_seconds"] = round(time.perf_counter() - started, 1)
    meta["summary"] = summary
    (out / "meta.json").write_text(json.dumps(meta, indent=1))


def _read_clips(
    mocap_dir: Path, files: list[Path], cfg: WorldConfig, progress: Callable[[int, int, str], None] | None
) -> tuple[list[Motion3D], list[str], list[dict[str, str]]]:
    """The usable clips at the world's frame rate, their paths relative to ``mocap_dir``, and the skipped files
    with the reason (unreadable, or shorter than a window). InputError when none is usable."""
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
    return motions, rels, skipped


def _write_split(out: Path, split: str, motions: list[Motion3D], chars: list[Skeleton], cfg: WorldConfig
                 ) -> tuple[np.ndarray, int]:
    """Write one split's arrays: the source clips, every clip replayed on every character, the window starts.

    Returns:
        The clips' first frames in the concatenated frames [clips] int64, and the number of windows.
    """
    frames = [m.num_frames for m in motions]
    offsets = np.concatenate([[0], np.cumsum(frames)[:-1]]).astype(np.int64)
    total = int(sum(frames))
    # [C, F, 18, 3] written straight into the cache file, one character at a time.
    pos = np.lib.format.open_memmap(
        out / f"{split}_positions.npy", mode="w+", dtype=np.float32, shape=(len(chars), total, len(WORLD_JOINTS), 3)
    )
    src = np.lib.format.open_memmap(
        out / f"{split}_source.npy", mode="w+", dtype=np.float32, shape=(total, len(WORLD_JOINTS), 3)
    )
    for k, motion in enumerate(motions):
        src[offsets[k]: offsets[k] + frames[k]] = motion.positions
    for c, skel in enumerate(chars):
        for k, motion in enumerate(motions):
            pos[c, offsets[k]: offsets[k] + frames[k]] = retarget_3d(motion, skel).positions
    pos.flush()
    src.flush()
    del pos, src
    windows = [(k, s) for k, n in enumerate(frames) for s in strided_starts(n, cfg.window, cfg.stride)]
    np.save(out / f"{split}_windows.npy", np.array(windows, dtype=np.int64).reshape(-1, 2))
    return offsets, len(windows)


__all__ = ["assign_splits", "find_mocap_files", "make_characters", "motion_group", "write_world"]
