"""`clone train-prior`: a generator prior from the project's synthetic performers, the start of `clone train-ref`.

    clone train-prior --mocap ../shared/mocap --steps 10000 --out runs/prior.pt --export prior_256.pt
    clone train-prior --mocap ../shared/mocap --steps 20000 --out runs/prior.pt --resume --export prior_256.pt
    clone train-prior --mocap ../shared/mocap --steps 10000 --out runs/more.pt --init prior_256.pt --export more_256.pt
    clone train-ref REF.mp4 --size 256 --init prior_256.pt
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from clone.cli.cloning import MAX_MINUTES, MAX_SIZE, MAX_STEPS, MIN_SIZE
from clone.cli.common import DEVICE_HELP, MAX_THREADS, console, training_device, user_errors
from clone.cli.progress import progress_bar, training_progress
from pose_io.errors import InputError

MAX_PERFORMERS = 4096
MAX_FRAMES = 1000
# Frames of all performers are held in memory: 256² RGB is 192 KiB a frame.
MAX_PRIOR_BYTES = 8 << 30


@user_errors
def train_prior_command(
    mocap: Annotated[Path, typer.Option("--mocap", help="Motion capture folder (BVH, AMC; searched recursively).")],
    out: Annotated[Path, typer.Option(
        "--out", "-o", help="The prior run's model file, with its training state (resume it with --resume).")],
    export: Annotated[Path | None, typer.Option(
        "--export", help="Also write the compact prior here (float16, no optimiser state): what "
        "`clone train-ref --init` reads.")] = None,
    size: Annotated[int, typer.Option("--size", help="Canvas size (a power of two).")] = 256,
    performers: Annotated[int, typer.Option("--performers", help="How many synthetic performers.")] = 128,
    frames: Annotated[int, typer.Option("--frames", help="Consecutive frames of each.")] = 40,
    plain_share: Annotated[float, typer.Option(
        "--plain-share", help="Share of performers in one-colour shirts (the rest striped or checked).")] = 1.0,
    seed: Annotated[int, typer.Option("--seed", help="Draws the performers.")] = 0,
    steps: Annotated[int | None, typer.Option(
        "--steps", help="Stop when the prior has this many steps in all (default 2000 without --minutes).")] = None,
    minutes: Annotated[float | None, typer.Option("--minutes", help="Stop after this many minutes.")] = None,
    resume: Annotated[bool, typer.Option("--resume", help="Continue the run at --out (the same performers).")] = False,
    init: Annotated[Path | None, typer.Option(
        "--init", help="Start a new run from this prior's (or model's) networks, e.g. an --export of an "
        "earlier run, to train it further without its optimiser state.")] = None,
    overwrite: Annotated[bool, typer.Option("--overwrite", help="Replace an existing run at --out.")] = False,
    device: Annotated[str, typer.Option("--device", help=DEVICE_HELP)] = "auto",
    threads: Annotated[int | None, typer.Option("--threads", min=1, help="CPU threads (default: free cores).")] = None,
) -> None:
    """Train a generator prior on synthetic performers: what `clone train-ref --init` starts a reference from.

    Licence-clean: the project's own characters replaying the motion capture under --mocap.

    Each performer is a random character, clip, view and backdrop, rendered and cut to its canvas as a video is.

    The run is a `clone train-ref` run over all of them (generator, discriminator, face pass); --resume continues
    it with the performers it was started with (--performers, --frames and --seed are then the stored ones).
    """
    from clone.train_ref import TrainConfig
    from clone.train_ref.prior import PriorConfig, export_prior, train_prior
    from pose_io.outputs import check_number, check_output

    if not (MIN_SIZE <= size <= MAX_SIZE and size & (size - 1) == 0):
        raise InputError(f"--size: must be a power of two from {MIN_SIZE} to {MAX_SIZE}, got {size}")
    check_number("--performers", performers, 1, MAX_PERFORMERS)
    check_number("--frames", frames, 2, MAX_FRAMES)
    check_number("--plain-share", plain_share, 0, 1)
    check_number("--seed", seed, 0, 2**31 - 1)
    check_number("--steps", steps, 1, MAX_STEPS)
    check_number("--minutes", minutes, 0, MAX_MINUTES, low_open=True)
    check_number("--threads", threads, 1, MAX_THREADS)
    need = performers * frames * size * size * 3
    if need > MAX_PRIOR_BYTES:
        raise InputError(f"--performers {performers} x --frames {frames} at {size}² would hold "
                         f"{need / 2**30:.1f} GiB of frames in memory (at most {MAX_PRIOR_BYTES / 2**30:.0f})")
    if init is not None and resume:
        raise InputError("--init starts a new prior run; --resume continues one: pass only one of them")
    if init is not None and not init.is_file():
        raise InputError(f"--init {init}: no such file")
    if not mocap.is_dir():
        raise InputError(f"--mocap {mocap}: no such folder")
    check_output(out, "--out", overwrite=overwrite, replaceable=resume)
    if export is not None:
        if export.resolve() == out.resolve():
            raise InputError("--export: give another file than --out (the run keeps its training state)")
        # an earlier export of the run being resumed is what --resume refreshes
        check_output(export, "--export", overwrite=overwrite or resume)
    dev = training_device(device, threads)
    config = None if resume else TrainConfig(size=size)
    prior = PriorConfig(performers=performers, frames=frames, plain_share=plain_share, seed=seed)

    with progress_bar("train-prior", count=False, elapsed=True) as bar:

        update = training_progress(bar, {"rendering": "rendering performers"})

        path, done = train_prior(mocap, out, config=config, prior=prior, steps=steps, minutes=minutes, device=dev,
                                 resume=resume, overwrite=overwrite, progress=update, grow_threads=threads is None,
                                 init=init)
    console.print(f"wrote {path} ({done} steps in all; --resume continues it)")
    if export is not None:
        export_prior(path, export, overwrite=True)
        console.print(f"wrote {export} ({export.stat().st_size / 2**20:.1f} MiB): clone train-ref --init {export}")
