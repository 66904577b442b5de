"""`clone world ...`: the motion world (mocap replayed on many characters and views) used for training."""

from __future__ import annotations

import time
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from clone.cli.common import WorldCacheOption, user_errors
from clone.cli.progress import progress_bar

if TYPE_CHECKING:
    from retarget.world.cache import CachedWorld

world_app = typer.Typer(no_args_is_help=True, help="Build and inspect the motion world used for training.")


@world_app.command("build")
@user_errors
def build(
    mocap: Annotated[
        Path, typer.Option("--mocap", help="Folder of .bvh / .bvh.gz / .amc files (searched recursively).")
    ],
    cache: WorldCacheOption = None,
    seed: Annotated[int, typer.Option("--seed", help="Seed of the motion split and the characters.")] = 0,
    fps: Annotated[float, typer.Option("--fps", help="Frame rate every clip is resampled to.")] = 30.0,
    train_characters: Annotated[
        int, typer.Option("--train-characters", min=1, help="Sampled training characters.")
    ] = 64,
    val_characters: Annotated[int, typer.Option("--val-characters", min=1, help="Sampled validation characters.")] = 8,
    test_characters: Annotated[
        int, typer.Option("--test-characters", min=1, help="Sampled test characters (+ named).")
    ] = 8,
    window: Annotated[int, typer.Option("--window", min=2, help="Window length in frames.")] = 64,
    stride: Annotated[int, typer.Option("--stride", min=1, help="Step between windows.")] = 32,
    rebuild: Annotated[bool, typer.Option("--rebuild", help="Build again even if the cache has this world.")] = False,
) -> None:
    """Build (or open from the cache) the motion world and print its summary."""

    from pose_io.errors import InputError
    from pose_io.outputs import check_number, check_writable_folder
    from retarget.world import MotionWorld

    check_number("--fps", fps, 0, 1000.0, low_open=True)
    for name, value in (("--train-characters", train_characters), ("--val-characters", val_characters),
                        ("--test-characters", test_characters)):
        check_number(name, value, 1, 10_000)
    check_number("--window", window, 2, 100_000)
    check_number("--stride", stride, 1, 100_000)
    if not mocap.is_dir():
        raise InputError(f"--mocap {mocap}: no such folder")
    if cache is not None:
        if cache.exists() and not cache.is_dir():
            raise InputError(f"--cache {cache}: is a file; give a folder")
        check_writable_folder(cache, f"--cache {cache}")
    started = time.perf_counter()
    with progress_bar("loading mocap", elapsed=True, remaining=False) as bar:

        def progress(done: int, total: int, what: str) -> None:
            bar(done, total, text=what)

        world = MotionWorld.build(
            mocap, cache, seed=seed, fps=fps, n_train_characters=train_characters,
            n_val_characters=val_characters, n_test_characters=test_characters, window=window, stride=stride,
            rebuild=rebuild, progress=progress,
        )
    elapsed = time.perf_counter() - started
    summary = world.summary()

    cols = ("split", "clips", "motions", "frames", "windows", "chars", "views", "samples", "height m", "3D MB")
    rows = [cols]
    for name, s in summary["splits"].items():
        lo, hi = s["height_range_m"]
        rows.append((
            name, str(s["clips"]), str(s["motions"]), str(s["frames"]), str(s["windows"]), str(s["characters"]),
            str(s["views"]), f"{s['samples']:,}", f"{lo:.2f}-{hi:.2f}", f"{s['positions_mb']:.0f}",
        ))
    widths = [max(len(r[k]) for r in rows) for k in range(len(cols))]
    typer.echo(f"motion world: {summary['fps']:g} fps, windows of {summary['window']} frames, stride {summary['stride']}")
    for r in rows:
        typer.echo("  ".join(v.rjust(w) for v, w in zip(r, widths)))
    for source, s in summary["sources"].items():
        typer.echo(f"source {source}: {s['clips']} clips, {s['frames']} frames")
    if summary["skipped"]:
        typer.echo(f"skipped {len(summary['skipped'])} files:")
        for item in summary["skipped"]:
            typer.echo(f"  {item['path']}: {item['reason']}")
    typer.echo(f"views: yaw {summary['view_yaws'][0]:g}..{summary['view_yaws'][-1]:g} deg in {summary['views']} bins, "
               f"pitch +-{summary['pitch_range_deg']:g} deg")
    typer.echo(f"built in {summary['build_seconds']:.1f} s; this run took {elapsed:.1f} s")
    typer.echo(f"cache: {summary['cache']}")


def _describe(world: CachedWorld) -> str:
    """One line of settings: characters per split (extra ones with their spread), seed, frame rate, window."""
    c = world.config
    if not world.finished:
        return "unfinished build"
    extra = c.get("extra_train_characters", 0)
    train = f"{c.get('n_train_characters')}" + (f"+{extra} at spread {c.get('extra_spread', 1.0):g}" if extra else "")
    return (f"characters {train} / {c.get('n_val_characters')} / {c.get('n_test_characters')}, seed {c.get('seed')}, "
            f"{c.get('fps', 0):g} fps, window {c.get('window')}")


@world_app.command("list")
@user_errors
def list_worlds(cache: WorldCacheOption = None) -> None:
    """List the cached worlds, most recently used first, with their size and settings."""
    from retarget.world.cache import cached_worlds

    worlds = cached_worlds(cache)
    for w in worlds:
        used = time.strftime("%Y-%m-%d %H:%M", time.localtime(w.last_used))
        typer.echo(f"{w.path.name}  {w.bytes / 1e9:6.2f} GB  used {used}  {_describe(w)}")
    typer.echo(f"{len(worlds)} world(s), {sum(w.bytes for w in worlds) / 1e9:.2f} GB")


@world_app.command("clean")
@user_errors
def clean(
    cache: WorldCacheOption = None,
    keep: Annotated[int, typer.Option("--keep", min=0, max=1000, help="Most recently used worlds kept.")] = 1,
    dry_run: Annotated[bool, typer.Option("--dry-run", help="Only say what would be removed.")] = False,
) -> None:
    """Remove all cached worlds but the --keep most recently used (and builds that never finished, after a day).

    A removed world is rebuilt from the mocap the next time training asks for it (minutes).
    """
    from retarget.world.cache import cached_worlds, remove_worlds, stale_worlds

    stale = stale_worlds(cached_worlds(cache), keep)
    for w in stale:
        typer.echo(f"{'would remove' if dry_run else 'removing'} {w.path} ({w.bytes / 1e9:.2f} GB; {_describe(w)})")
    freed = sum(w.bytes for w in stale) if dry_run else remove_worlds(stale)
    typer.echo(f"{'would free' if dry_run else 'freed'} {freed / 1e9:.2f} GB ({len(stale)} world(s))")
