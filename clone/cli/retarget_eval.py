"""`clone retarget eval`: our network against the baselines and the authors' models on a world split, extra
mocap and real tracks, with the codes' silhouettes.

torch is imported inside the command so that `clone --help` stays fast.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from clone.cli.choices import Split
from clone.cli.common import (
    DEVICE_HELP,
    MAX_CLIP_FRAMES,
    MAX_REFINE_STEPS,
    MAX_THREADS,
    CompareOption,
    MocapOption,
    OurWeightsOption,
    WorldCacheOption,
    WorldSeedOption,
    console,
    named_checkpoints,
    user_errors,
)
from clone.cli.progress import progress_bar
from retarget.inference.config import REFINE_STEPS  # numpy and pose_io only: light for the command line

# Ranges of options that scale time or memory, checked before any work (and MAX_CLIP_FRAMES).
MAX_PAIRS = 1_000_000
MAX_CODE_GRIDS = 1_000  # 216 windows each
MAX_PROBE_STEPS = 1_000_000


@user_errors
def evaluate(
    mocap: MocapOption,
    out: Annotated[Path, typer.Option("--out", help="Folder to write: eval.json, eval.md, codes_*.png.")],
    weights: OurWeightsOption = None,
    compare: CompareOption = None,
    official: Annotated[
        Path | None,
        typer.Option("--official", help="Folder of the authors' pretrained_{full,skeleton,view}.pth and .npy."),
    ] = None,
    bvh: Annotated[
        list[Path] | None, typer.Option("--bvh", help="Extra mocap file replayed on the test characters (repeatable).")
    ] = None,
    real: Annotated[
        Path | None,
        typer.Option("--real", help="Folder of OpenPose folders: every ordered pair retargeted and measured."),
    ] = None,
    pairs: Annotated[int, typer.Option("--pairs", min=1, help="Cases per source (split, extra mocap).")] = 500,
    length: Annotated[int, typer.Option("--length", min=16, help="Frames per case.")] = 64,
    reference_length: Annotated[
        int, typer.Option("--reference-length", min=16, help="Frames of a case's reference (a reference video is "
                          "longer than the paper's 64).")
    ] = 64,
    max_yaw: Annotated[
        float, typer.Option("--max-yaw", help="Cameras are view bins within +-this many degrees of the front (90: "
                            "all 13, the paper's protocol; 45: the views of most videos, which cloning meets).")
    ] = 90.0,
    max_pitch: Annotated[
        float, typer.Option("--max-pitch", help="Cameras' pitch is drawn in +-this many degrees (the world's: 10).")
    ] = 10.0,
    seed: Annotated[int, typer.Option("--seed", help="Seed of the cases.")] = 0,
    noise: Annotated[
        float, typer.Option("--noise", help="Detector noise on the inputs: Gaussian, std as a fraction of the "
                            "person's height (real OpenPose tracks: about 0.002-0.006).")
    ] = 0.0,
    turns: Annotated[
        bool, typer.Option("--turns/--no-turns", help="Also score turn cases: the split's windows each turned by "
                           "90-360 degrees about the vertical, and its windows that turn by over 90 as captured.")
    ] = True,
    split: Annotated[Split, typer.Option("--split", parser=Split, help="World split to measure on.")] = Split.TEST,
    code_grids: Annotated[
        int, typer.Option("--code-grids", min=1, help="Silhouette grids (6 motions x 6 characters x 6 views each, "
                          "drawn anew) averaged; 1: the paper's single grid.")
    ] = 10,
    probe_steps: Annotated[
        int, typer.Option("--probe-steps", help="Also train a proportion probe for this many steps (about 4,000: 2 "
                          "CPU minutes, 230 MB) on the training split's windows, reading only each character's bone "
                          "lengths over its height, and score it as a skeleton code: a reference point for the skeleton "
                          "codes' silhouette. 0: no probe.")
    ] = 0,
    refine_steps: Annotated[
        int | None,
        typer.Option("--refine-steps", help="Motion-code refinement steps of ours and the --compare rows (default: "
                     f"inference's, {REFINE_STEPS}; 0: the network alone). The authors' rows always run as released."),
    ] = None,
    world_seed: WorldSeedOption = 0,
    cache: WorldCacheOption = None,
    threads: Annotated[int | None, typer.Option("--threads", min=1, help="CPU threads (default: the free cores).")] = None,
    device: Annotated[str, typer.Option("--device", help=DEVICE_HELP)] = "auto",
    overwrite: Annotated[bool, typer.Option("--overwrite", help="Replace an existing --out.")] = False,
) -> None:
    """Retargeting error of our network vs baselines on unseen motions and characters, and code silhouettes."""

    from pose_io.errors import InputError
    from pose_io.outputs import FOLDER, check_number, check_output
    from retarget.evaluate import EvalConfig, run_eval
    from retarget.runtime import configure_threads
    from retarget.world import MotionWorld

    check_output(out, "--out", suffixes=(FOLDER,), overwrite=overwrite)
    check_number("--pairs", pairs, 1, MAX_PAIRS)
    check_number("--length", length, 16, MAX_CLIP_FRAMES)
    check_number("--reference-length", reference_length, 16, MAX_CLIP_FRAMES)
    check_number("--max-yaw", max_yaw, 0, 90)
    check_number("--max-pitch", max_pitch, 0, 60)
    check_number("--noise", noise, 0, 0.1)
    check_number("--code-grids", code_grids, 1, MAX_CODE_GRIDS)
    check_number("--probe-steps", probe_steps, 0, MAX_PROBE_STEPS)
    check_number("--threads", threads, 1, MAX_THREADS)
    check_number("--refine-steps", refine_steps, 0, MAX_REFINE_STEPS)
    if not mocap.is_dir():
        raise InputError(f"--mocap {mocap}: no such folder")
    named = named_checkpoints(compare)
    real_tracks = None
    if real is not None:
        from retarget.training.run import read_real_tracks

        real_tracks = dict(read_real_tracks(real, named=True))
    configure_threads(threads)
    world = MotionWorld.build(mocap, cache, seed=world_seed)
    with progress_bar("eval") as bar:
        doc, table = run_eval(
            world.split(split.value), out, weights=weights, compare=named, official=official, bvh=bvh or (), real=real_tracks,
            config=EvalConfig(pairs=pairs, length=length, reference_length=reference_length, seed=seed, max_yaw=max_yaw,
                              max_pitch=max_pitch, noise=noise, code_grids=code_grids,
                              probe_steps=probe_steps, turns=turns),
            fps=world.config.fps, device=device,
            overwrite=overwrite, world_seed=world_seed, refine_steps=refine_steps,
            probe_split=world.split("train") if probe_steps else None,
            progress=bar,
        )
    typer.echo(table)
    console.print(f"wrote {out}: eval.json, eval.md and {len(doc['silhouettes'])} code plots in {doc['seconds']:.0f} s")
