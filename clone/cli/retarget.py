"""`clone retarget`: move a driver's motion onto a reference person's skeleton and view, blend codes
(`train`, `eval` and `eval-cloning` live in :mod:`clone.cli.retarget_train`, :mod:`clone.cli.retarget_eval` and
:mod:`clone.cli.retarget_cloning`).

torch and the pose readers are imported inside the commands so that `clone --help` stays fast, and `apply`
imports no torch at all when the weights have a numpy export (``--backend auto``, the shipped weights).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from clone.cli.choices import OutputFormat
from clone.cli.common import (
    DEVICE_HELP,
    MAX_CLIP_FRAMES,
    MAX_REFINE_STEPS,
    MAX_THREADS,
    console,
    user_errors,
)
from clone.cli.progress import progress_bar
from clone.cli.retarget_cloning import eval_cloning
from clone.cli.retarget_eval import evaluate
from clone.cli.retarget_train import train
from retarget.inference.config import REFINE_STEPS  # numpy and pose_io only: light for the command line

retarget_app = typer.Typer(
    help="Retarget 2D motion to another person's skeleton and camera view (Aberman et al. 2019).",
    no_args_is_help=True,
)

_SIZE_HELP = "Image size WxH of inputs that store none (OpenPose JSON); default: inferred from the data."


@retarget_app.command("apply")
@user_errors
def apply(
    motion_poses: Annotated[
        list[Path],
        typer.Argument(help="Driver's poses (OpenPose folder, COCO/AlphaPose JSON, npz, npy, csv); several, or a "
                       "folder of them, are retargeted together in one run (--out is then a folder)."),
    ],
    skeleton: Annotated[Path, typer.Option("--skeleton", help="Reference person's poses: skeleton, placement, frame.")],
    out: Annotated[Path, typer.Option("--out", help="Output: a folder (OpenPose JSON), or a .npz / .csv file; with "
                                      "several inputs a folder that gets one output per input, named after it.")],
    view: Annotated[
        Path | None, typer.Option("--view", help="Poses whose camera view to use (default: --skeleton's).")
    ] = None,
    preview: Annotated[Path | None, typer.Option("--preview", help="Also draw the result into this .mp4.")] = None,
    weights: Annotated[
        Path | None,
        typer.Option("--weights", help="clone2d checkpoint (or its numpy export, .npz, which runs without "
                     "refinement), or the authors' pretrained_*.pth (default: shipped)."),
    ] = None,
    size: Annotated[str | None, typer.Option("--size", help=_SIZE_HELP)] = None,
    device: Annotated[str, typer.Option("--device", help=DEVICE_HELP)] = "auto",
    backend: Annotated[
        str, typer.Option("--backend", help="auto | numpy | torch. auto: numpy on the CPU (torch is not even "
                          "imported) when the weights have an up-to-date .npz export beside them (the shipped "
                          "ones do), else torch. Both refine motion codes, to the same result.")
    ] = "auto",
    refine_steps: Annotated[
        int | None,
        typer.Option("--refine-steps", help="Gradient steps that refine each driver window's motion code so the "
                     f"driver's range of motion is kept (default {REFINE_STEPS}, chosen on validation). 0: the "
                     "encoder's code as it is."),
    ] = None,
    to: Annotated[
        OutputFormat | None,
        typer.Option("--to", parser=OutputFormat, help="Format of the outputs of several inputs (default npz)."),
    ] = None,
    threads: Annotated[int | None, typer.Option("--threads", min=1, help="CPU threads (default: the free cores).")] = None,
    overwrite: Annotated[bool, typer.Option("--overwrite", help="Replace existing outputs.")] = False,
    foot_lock: Annotated[bool, typer.Option(
        "--foot-lock/--no-foot-lock", help="Hold the feet still while the driver's feet touch the ground "
        "(the body moved against the slide, then the ankles; knees re-solved).")] = True,
) -> None:
    """Retarget MOTION_POSES onto the person of --skeleton; write body15 poses in that person's frame."""
    from pose_io.errors import InputError
    from pose_io.folders import find_tracks
    from pose_io.outputs import FOLDER, check_number, check_output
    from pose_io.readers import parse_size, read_track
    from retarget.inference.batch import is_batch, retarget_files

    check_number("--threads", threads, 1, MAX_THREADS)
    check_number("--refine-steps", refine_steps, 0, MAX_REFINE_STEPS)
    batch = is_batch(motion_poses)
    # Every output is checked before any work: a bad --preview must not fail after --out is written.
    if batch:
        if preview is not None:
            raise InputError("--preview draws one result; it takes a single input")
        fmt = to.value if to is not None else "npz"
        motions = [f.path for f in find_tracks(motion_poses, recursive=False, duplicates="refuse")]
        outputs = _batch_outputs(out, motions, fmt, overwrite)
    else:
        if to is not None:
            raise InputError("--to sets the format of several inputs' outputs; with one input --out's name does")
        check_output(out, "--out", suffixes=(FOLDER, ".npz", ".csv"), overwrite=overwrite)
        if preview is not None:
            check_output(preview, "--preview", suffixes=(".mp4",), overwrite=overwrite)
            if preview.absolute() == out.absolute():
                raise InputError(f"--preview {preview}: the same path as --out")
    image_size = parse_size(size) if size else None
    motion = None if batch else read_track(motion_poses[0], image_size=image_size)
    reference = read_track(skeleton, image_size=image_size)
    view_track = read_track(view, image_size=image_size) if view is not None else None
    retargeter = _retargeter(weights, device, backend, threads, refine_steps)
    codes = retargeter.reference_codes(reference, view_track, name=str(skeleton), view_name=str(view))
    if foot_lock:
        from retarget.inference.foot_lock import FootLockedRetargeter

        retargeter = FootLockedRetargeter(retargeter)
    if batch:
        with progress_bar("retargeting") as update:
            frames = retarget_files(retargeter, codes, motions, outputs, fmt=fmt, overwrite=overwrite,
                                    read=lambda p: read_track(p, image_size=image_size), progress=update)  # fmt: skip
        console.print(f"wrote {len(outputs)} {'clip' if len(outputs) == 1 else 'clips'} to {out} ({frames:,} frames, "
                      f"{fmt}, body15, {codes.image_size[0]}x{codes.image_size[1]})")  # fmt: skip
        return
    from pose_io.writers import write_track

    result = retargeter.retarget(motion, codes, name=str(motion_poses[0]))
    write_track(result, out, overwrite=overwrite)
    console.print(f"wrote {out} ({len(result)} frames, body15, {result.image_size[0]}x{result.image_size[1]})")
    if preview is not None:
        from pose_io.video_out import write_pose_video

        write_pose_video(result, preview, overwrite=overwrite)
        console.print(f"wrote {preview}")


def _batch_outputs(out: Path, motions: list[Path], fmt: str, overwrite: bool) -> list[Path]:
    """The outputs of several inputs inside the folder --out, each checked (InputError before any work)."""
    from pose_io.errors import InputError
    from pose_io.outputs import check_output, check_writable_folder
    from retarget.inference.batch import batch_outputs

    if out.exists() and not out.is_dir():
        raise InputError(f"--out {out}: is a file; several inputs are written into a folder")
    if out.suffix and not out.exists():
        raise InputError(f"--out {out}: several inputs are written into a folder; give one without a suffix")
    check_writable_folder(out, f"--out {out}")
    outputs = batch_outputs(motions, out, fmt)
    for path in outputs:
        check_output(path, "--out", overwrite=overwrite)
    return outputs


def _retargeter(
    weights: Path | None, device: str, backend: str, threads: int | None, refine_steps: int | None
):  # -> RetargeterBase
    """The network for --weights/--device/--backend/--refine-steps, its threads set (BLAS threads for numpy,
    torch's otherwise)."""
    from retarget.api import NumpyRetargeter, load_retargeter
    from retarget.inference.config import InferenceConfig
    from retarget.network.blas import set_blas_threads
    from retarget.runtime import free_cores

    config = InferenceConfig() if refine_steps is None else InferenceConfig(refine_steps=refine_steps)
    retargeter = load_retargeter(weights, device, config, backend=backend.strip().lower())
    if isinstance(retargeter, NumpyRetargeter):
        set_blas_threads(threads or free_cores())
    elif retargeter.device.type == "cpu":
        from retarget.runtime import configure_threads

        configure_threads(threads)
    return retargeter


retarget_app.command("train")(train)


retarget_app.command("eval")(evaluate)
retarget_app.command("eval-cloning")(eval_cloning)


@retarget_app.command("interpolate")
@user_errors
def interpolate(
    a: Annotated[Path, typer.Argument(help="Clip A's poses: the grid's top-left corner; its third attribute is kept.")],
    b: Annotated[Path, typer.Argument(help="Clip B's poses: the grid's bottom-right corner.")],
    out: Annotated[Path, typer.Option("--out", help="Output: .mp4 (the grid drawn) or .npz (poses [S, S, T, 15, 2]).")],
    vary: Annotated[
        str, typer.Option("--vary", help="The two attributes blended, rows first: motion,view | motion,body | body,view.")
    ] = "motion,view",
    steps: Annotated[int, typer.Option("--steps", min=2, max=16, help="Cells per axis.")] = 5,
    frames: Annotated[
        int, typer.Option("--frames", min=8, help="At most this many frames; both clips are cut to the shorter one.")
    ] = 120,
    canvas: Annotated[
        str,
        typer.Option("--canvas", help="video: A's frame, codes and smoothing as `retarget apply`; authors: their "
                     "interpolate.py (512-pixel canvas, root from (256, 256), whole-clip codes, no smoothing)."),
    ] = "video",
    cell: Annotated[int, typer.Option("--cell", min=32, max=512, help="Side of one cell of the video in pixels.")] = 128,
    weights: Annotated[
        Path | None,
        typer.Option("--weights", help="clone2d checkpoint, or the authors' pretrained_full.pth (default: shipped)."),
    ] = None,
    size: Annotated[str | None, typer.Option("--size", help=_SIZE_HELP)] = None,
    device: Annotated[str, typer.Option("--device", help=DEVICE_HELP)] = "auto",
    overwrite: Annotated[bool, typer.Option("--overwrite", help="Replace an existing --out.")] = False,
) -> None:
    """Blend two attributes of A's and B's codes on a STEPS x STEPS grid (paper Fig. 1); the third stays A's."""
    import time

    import numpy as np

    from pose_io.atomic import atomic_file
    from pose_io.errors import InputError
    from pose_io.outputs import check_number, check_output
    from pose_io.readers import parse_size, read_track
    from pose_io.video_out import VideoWriter
    from retarget.api import load_retargeter
    from retarget.applications.interpolate import CANVASES, grid_frames, interpolate_grid, parse_vary
    from retarget.runtime import configure_threads

    start = time.perf_counter()
    check_output(out, "--out", suffixes=(".mp4", ".npz"), overwrite=overwrite)
    check_number("--frames", frames, 8, MAX_CLIP_FRAMES)
    if canvas not in CANVASES:
        raise InputError(f"--canvas {canvas!r}; valid: {', '.join(CANVASES)}")
    rows, cols = parse_vary(vary)
    image_size = parse_size(size) if size else None
    clip_a, clip_b = read_track(a, image_size=image_size), read_track(b, image_size=image_size)
    configure_threads()
    retargeter = load_retargeter(weights, device)
    grid = interpolate_grid(retargeter, clip_a, clip_b, (rows, cols), steps, frames, canvas, names=(a.name, b.name))
    if out.suffix.lower() == ".npz":
        with atomic_file(out, overwrite=overwrite) as tmp, open(tmp, "wb") as f:
            np.savez_compressed(f, **grid.to_arrays())
    else:
        with VideoWriter(out, grid.fps, overwrite=overwrite) as video:
            for frame in grid_frames(grid, cell):
                video.write(frame)
    length = grid.poses.shape[2]
    console.print(f"wrote {out} ({steps}x{steps} cells, {length} frames; {rows} down, {cols} across, {grid.kept} of "
                  f"{a.name}; {canvas} canvas) in {time.perf_counter() - start:.1f} s")
