"""`clone search`: find a motion in a collection of pose tracks, whoever performs it, from whichever side.

torch and the pose readers are imported inside the commands so that `clone --help` stays fast.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer

from clone.cli.common import (
    DEVICE_HELP,
    MocapOption,
    WorldCacheOption,
    WorldSeedOption,
    console,
    resolve_device_option,
    user_errors,
)
from clone.cli.progress import progress_bar

search_app = typer.Typer(
    help="Motion retrieval: index pose tracks by their motion codes, then find a query's motion in them.",
    no_args_is_help=True,
)

_WEIGHTS_HELP = "clone2d checkpoint, or the authors' pretrained_*.pth (default: shipped); the index remembers which."
_SIZE_HELP = "Image size WxH of inputs that store none (OpenPose JSON); default: inferred from the data."
_THREADS_HELP = "CPU threads (default: the free cores)."


@search_app.command("index")
@user_errors
def index(
    tracks: Annotated[
        list[Path],
        typer.Argument(help="Pose files and folders (OpenPose folder, COCO/AlphaPose JSON, npz, npy, csv); other "
                       "folders are searched recursively."),
    ],
    out: Annotated[Path, typer.Option("--out", help="Index file to write (one .npz file, any name).")],
    weights: Annotated[Path | None, typer.Option("--weights", help=_WEIGHTS_HELP)] = None,
    size: Annotated[str | None, typer.Option("--size", help=_SIZE_HELP)] = None,
    device: Annotated[str, typer.Option("--device", help=DEVICE_HELP)] = "auto",
    threads: Annotated[int | None, typer.Option("--threads", min=1, help=_THREADS_HELP)] = None,
    overwrite: Annotated[bool, typer.Option("--overwrite", help="Replace an existing --out.")] = False,
) -> None:
    """Encode the motion of every track once and write the index to --out."""

    from pose_io.outputs import check_number, check_output
    from pose_io.readers import parse_size, read_track
    from retarget.api import load_retargeter
    from retarget.applications.search import MotionCodeEncoder, build_index, save_index

    check_output(out, "--out", overwrite=overwrite)
    check_number("--threads", threads, 1, 1024)
    image_size = parse_size(size) if size else None
    dev = resolve_device_option(device, threads)
    encoder = MotionCodeEncoder(load_retargeter(weights, str(dev)))
    with progress_bar("indexing") as bar:
        built, skipped = build_index(
            tracks, encoder, read=lambda p: read_track(p, image_size=image_size),
            progress=lambda done, total, _: bar(done, total),
        )
    save_index(built, out, overwrite=overwrite)
    if skipped:
        console.print(f"skipped {len(skipped)} unreadable file(s), first: {skipped[0].reason}", highlight=False)
    typer.echo(f"wrote {out} ({built.num_tracks} tracks, {built.num_frames:,} frames)")


@search_app.command("query")
@user_errors
def query(
    query_poses: Annotated[Path, typer.Argument(help="The query's poses (any format `clone pose info` reads).")],
    index_path: Annotated[Path, typer.Option("--index", help="Index written by `clone search index`.")],
    top: Annotated[int, typer.Option("--top", min=1, help="Hits to show.")] = 10,
    per_track: Annotated[int, typer.Option("--per-track", min=1, help="Most hits from one track.")] = 1,
    as_json: Annotated[bool, typer.Option("--json", help="Print the hits as JSON instead of a table.")] = False,
    weights: Annotated[Path | None, typer.Option("--weights", help="The weights the index was built with.")] = None,
    size: Annotated[str | None, typer.Option("--size", help=_SIZE_HELP)] = None,
    device: Annotated[str, typer.Option("--device", help=DEVICE_HELP)] = "auto",
    threads: Annotated[int | None, typer.Option("--threads", min=1, help=_THREADS_HELP)] = None,
) -> None:
    """The indexed tracks that hold QUERY_POSES' motion, best first: frames start..end-1 of each, and the score
    (cosine similarity of the motion codes, 1 = the same codes)."""
    from rich.console import Console
    from rich.table import Table

    from pose_io.outputs import check_number
    from pose_io.readers import parse_size, read_track
    from retarget.api import load_retargeter
    from retarget.applications.search import MotionCodeEncoder, load_index, search

    check_number("--top", top, 1, 100_000)
    check_number("--per-track", per_track, 1, 100_000)
    check_number("--threads", threads, 1, 1024)
    image_size = parse_size(size) if size else None
    loaded = load_index(index_path)
    track = read_track(query_poses, image_size=image_size)
    dev = resolve_device_option(device, threads)
    encoder = MotionCodeEncoder(load_retargeter(weights, str(dev)))
    hits = search(loaded, encoder, track, top_k=top, per_track=per_track, name=str(query_poses))
    if as_json:
        doc = {"query": str(query_poses), "frames": len(track), "index": str(index_path),
               "hits": [h.to_dict() for h in hits]}  # fmt: skip
        typer.echo(json.dumps(doc, indent=1))
        return
    if not hits:
        console.print(f"no indexed track is as long as the query ({len(track)} frames)", highlight=False)
        return
    table = Table(title=f"{query_poses}: {len(track)} frames", title_justify="left")
    table.add_column("rank", justify="right")
    table.add_column("track", overflow="fold")  # long paths wrap instead of being cut
    for name in ("start", "end", "score"):
        table.add_column(name, justify="right")
    for rank, h in enumerate(hits, 1):
        table.add_row(str(rank), h.path, str(h.start), str(h.end), f"{h.score:.3f}")
    Console().print(table)


@search_app.command("eval")
@user_errors
def evaluate(
    mocap: MocapOption,
    queries: Annotated[int, typer.Option("--queries", min=1, help="Queries (random test windows).")] = 500,
    length: Annotated[int, typer.Option("--length", min=16, help="Frames per query.")] = 64,
    min_view_gap: Annotated[
        float,
        typer.Option("--min-view-gap", min=0.0, max=180.0, metavar="DEG",
                     help="A hit must be another character seen at least this many degrees of yaw from the "
                     "query's view (0: any other view bin)."),
    ] = 45.0,
    seed: Annotated[int, typer.Option("--seed", help="Seed of the index performances and the queries.")] = 0,
    weights: Annotated[Path | None, typer.Option("--weights", help=_WEIGHTS_HELP)] = None,
    out: Annotated[Path | None, typer.Option("--out", help="Also write the results as JSON here.")] = None,
    world_seed: WorldSeedOption = 0,
    cache: WorldCacheOption = None,
    device: Annotated[str, typer.Option("--device", help=DEVICE_HELP)] = "auto",
    threads: Annotated[int | None, typer.Option("--threads", min=1, help=_THREADS_HELP)] = None,
    overwrite: Annotated[bool, typer.Option("--overwrite", help="Replace an existing --out.")] = False,
) -> None:
    """Retrieval accuracy on the motion world's test split: motion codes against raw joints, each query's motion
    to be found performed by another character, seen at least --min-view-gap degrees of yaw away."""

    from pose_io.atomic import atomic_file
    from pose_io.errors import InputError
    from pose_io.outputs import check_number, check_output
    from retarget.api import load_retargeter
    from retarget.applications.search import MotionCodeEncoder
    from retarget.applications.search.evaluate import (
        RetrievalEvalConfig,
        evaluate_retrieval,
        markdown_table,
        summary,
    )
    from retarget.world import MotionWorld

    if out is not None:
        check_output(out, "--out", suffixes=(".json",), overwrite=overwrite)
    check_number("--queries", queries, 1, 1_000_000)
    check_number("--length", length, 16, 100_000)
    check_number("--threads", threads, 1, 1024)
    check_number("--min-view-gap", min_view_gap, 0, 180)
    if not mocap.is_dir():
        raise InputError(f"--mocap {mocap}: no such folder")
    config = RetrievalEvalConfig(queries=queries, length=length, min_view_gap=min_view_gap, seed=seed)
    dev = resolve_device_option(device, threads)
    encoder = MotionCodeEncoder(load_retargeter(weights, str(dev)))
    world = MotionWorld.build(mocap, cache, seed=world_seed)
    with progress_bar("queries") as bar:
        doc = evaluate_retrieval(world.split("test"), encoder, config, fps=world.config.fps,
                                 progress=bar)
    typer.echo(summary(doc))
    typer.echo(markdown_table(doc))
    if out is not None:
        with atomic_file(out, overwrite=overwrite) as tmp:
            Path(tmp).write_text(json.dumps(doc, indent=1) + "\n")
        console.print(f"wrote {out}", highlight=False)
