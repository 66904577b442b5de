"""`clone world ...`: the motion world (mocap replayed on many characters and views) used for training."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Annotated

import typer

from clone.cli.common import console, user_errors

world_app = typer.Typer(no_args_is_help=True, help="Build and inspect the motion world used for training.")


@world_app.command("build")
@user_errors
def build(
    mocap: Annotated[
        Path, typer.Option("--mocap", help="Folder of .bvh / .bvh.gz / .amc files (searched recursively).")
    ],
    cache: Annotated[
        Path | None, typer.Option("--cache", help="Cache folder (default: ~/.cache/clone2d/world).")
    ] = None,
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
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    from clone.outputs import check_number, check_writable_folder
    from pose_io.errors import InputError
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
    with Progress(
        TextColumn("loading mocap"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
        TextColumn("{task.description}"), console=console, transient=True,
    ) as bar:
        task = bar.add_task("", total=None)

        def progress(done: int, total: int, what: str) -> None:
            bar.update(task, completed=done, total=total, description=what)

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
