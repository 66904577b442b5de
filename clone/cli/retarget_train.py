"""`clone retarget train`: train the retargeting network on the motion world (and unlabelled real tracks).

torch is imported inside the command so that `clone --help` stays fast.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from clone.cli.choices import Ablation, Variant
from clone.cli.common import DEVICE_HELP, MAX_THREADS, WorldCacheOption, console, training_device, user_errors
from clone.cli.progress import progress_bar

# Ranges of options that scale time or memory, checked before any work.
MAX_MINUTES = 7 * 24 * 60.0
MAX_EPOCHS = 1_000_000
MAX_BATCH = 65_536
MAX_WORKERS = 256
MAX_EXTRA_CHARACTERS = 4096  # 11 MB of world cache each


@user_errors
def train(
    mocap: Annotated[Path, typer.Option("--mocap", help="Motion-capture folder the synthetic world is built from.")],
    out: Annotated[Path, typer.Option("--out", help="Checkpoint file to write (rewritten after every epoch).")],
    real: Annotated[
        Path | None, typer.Option("--real", help="Folder of OpenPose folders: unlabelled real tracks.")
    ] = None,
    minutes: Annotated[float | None, typer.Option("--minutes", min=0.0, help="Wall-clock budget of this run.")] = None,
    epochs: Annotated[
        int | None, typer.Option("--epochs", min=1, help="Total epochs (default 300 without --minutes).")
    ] = None,
    resume: Annotated[bool, typer.Option("--resume", help="Continue the run stored in --out.")] = False,
    best: Annotated[
        Path | None,
        typer.Option("--best", help="Also keep the weights of the epoch with the lowest validation retargeting "
                     "error (cross reconstruction plus root path) in this file, rewritten whenever an epoch beats "
                     "the run's earlier ones."),
    ] = None,
    average: Annotated[
        Path | None,
        typer.Option("--average", help="Also write the mean of the weights at the end of every epoch from "
                     "--average-from on to this file (rewritten after every epoch; kept in --out for --resume)."),
    ] = None,
    average_from: Annotated[
        int | None, typer.Option("--average-from", min=1, help="First epoch (over resumed runs) in --average "
                                 "(default: the resumed run's, else 1).")
    ] = None,
    variant: Annotated[
        Variant, typer.Option("--variant", parser=Variant, help="Network: three encoders, or without view or body.")
    ] = Variant.FULL,
    ablation: Annotated[
        Ablation,
        typer.Option("--ablation", parser=Ablation, help="Objective: the paper's, without triplet loss, or without "
                     "cross reconstruction."),
    ] = Ablation.FULL,
    cache: WorldCacheOption = None,
    seed: Annotated[int, typer.Option("--seed", help="Seed of every random choice.")] = 0,
    threads: Annotated[
        int | None, typer.Option("--threads", min=1, help="CPU threads (default: the free cores).")
    ] = None,
    workers: Annotated[int, typer.Option("--workers", min=0, help="Data-loader processes cutting world windows.")] = 0,
    device: Annotated[str, typer.Option("--device", help=DEVICE_HELP)] = "auto",
    init: Annotated[
        Path | None,
        typer.Option("--init", help="Start from these weights: a clone2d checkpoint or the authors' pretrained_*.pth."),
    ] = None,
    lr: Annotated[float, typer.Option("--lr", min=1e-7, max=1.0, help="Learning rate (1e-3 from scratch).")] = 1e-3,
    trajectory_weight: Annotated[
        float, typer.Option("--trajectory-weight", min=0.0, help="Weight of the integrated root-path loss (0 = the paper).")
    ] = 0.1,
    foot_weight: Annotated[float, typer.Option("--foot-weight", min=0.0, help="Weight of the foot-velocity loss.")] = 0.0,
    triplet_weight: Annotated[float, typer.Option("--triplet-weight", min=0.0, help="Weight of the triplet loss.")] = 0.3,
    triplet_margin: Annotated[float, typer.Option("--triplet-margin", min=0.0, help="Margin of the triplet loss.")] = 0.5,
    spread_weight: Annotated[
        float, typer.Option("--spread-weight", min=0.0, help="Weight of the range-of-motion loss (0 = the paper).")
    ] = 0.5,
    cycle_weight: Annotated[
        float, typer.Option("--cycle-weight", min=0.0, help="Weight of the cycle term on the --real tracks: a motion "
                            "moved onto another track and back should come back unchanged (0 = the paper).")
    ] = 0.0,
    skeleton_ratio_weight: Annotated[
        float, typer.Option("--skeleton-ratio-weight", min=0.0, help="Weight of a scale-free term asking each "
                            "skeleton code to lie 2x nearer its character's code from another motion and view than "
                            "another character's from the same motion and view (0 = the paper).")
    ] = 0.0,
    skeleton_cluster_weight: Annotated[
        float, typer.Option("--skeleton-cluster-weight", min=0.0, help="Weight of a scale-free term asking each "
                            "character's skeleton codes over 2 motions x 2 views to spread less than a share of their "
                            "distance to the nearest other character's in the batch (0 = the paper).")
    ] = 0.0,
    skeleton_cluster_ratio: Annotated[
        float, typer.Option("--skeleton-cluster-ratio", min=0.0, help="The spread --skeleton-cluster-weight asks "
                            "for, in distances to the nearest other character.")
    ] = 0.5,
    skeleton_proportion_weight: Annotated[
        float, typer.Option("--skeleton-proportion-weight", min=0.0, help="Weight of a term asking the distances "
                            "between skeleton codes to follow the distances between their characters' proportions "
                            "(0 = the paper).")
    ] = 0.0,
    extra_characters: Annotated[
        int, typer.Option("--extra-characters", min=0, help="Training characters added to the world's 64 (their "
                          "own random draws; validation and test characters unchanged).")
    ] = 0,
    extra_spread: Annotated[
        float, typer.Option("--extra-spread", min=0.1, max=4.0, help="Factor on the body-proportion spread of the "
                            "extra characters (1: like the world's).")
    ] = 1.0,
    max_pitch: Annotated[
        float, typer.Option("--max-pitch", help="Training cameras' pitch is drawn in +-this many degrees (the "
                            "world's: 10).")
    ] = 10.0,
    perspective: Annotated[
        float, typer.Option("--perspective", help="Share of training cameras that see in perspective from 2-8 m "
                            "(0: all weak-perspective, like the world's).")
    ] = 0.0,
    frontal_share: Annotated[
        float, typer.Option("--frontal-share", help="Share of training samples whose people are all seen from "
                            "within 45 degrees of the front, the views of most videos (0: every sample draws "
                            "from all 13 view bins, like the world).")
    ] = 0.0,
    turn_share: Annotated[
        float, typer.Option("--turn-share", help="Share of training motions given a whole-body turn of 90-360 "
                            "degrees about the vertical, in 3D before projection (0: the captured motion only).")
    ] = 0.0,
    splice_share: Annotated[
        float, typer.Option("--splice-share", help="Share of training motions whose torso, arms and head come from "
                            "another training motion, on the same body, in 3D before projection (0: none).")
    ] = 0.0,
    bend: Annotated[
        float, typer.Option("--bend", help="Smooth noise of this many degrees on every training motion's "
                            "upper-body joint angles, in 3D before projection; the legs keep theirs (0: none).")
    ] = 0.0,
    source_balance: Annotated[
        float, typer.Option("--source-balance", help="How evenly the motion-capture sources (the top folders "
                            "under --mocap) are drawn: a window's chance goes as its source's window count to "
                            "the power -B (0: every window alike; 1: every source alike).")
    ] = 0.0,
    # 64 = TrainConfig's default (the paper's): runs started without the option resume with it.
    batch_size: Annotated[
        int, typer.Option("--batch-size", min=1, help="Samples per step over all processes (under torchrun each "
                          "takes its share; the learning rate is that of one process).")
    ] = 64,
    amp: Annotated[
        bool | None, typer.Option("--amp/--no-amp", help="bfloat16 mixed precision on CUDA (default: on where the "
                                  "GPU supports it); ignored on the CPU.")
    ] = None,
) -> None:
    """Train the retargeting network on the motion world built from --mocap.

    The loss weights default to the recipe of the shipped weights (with --init pretrained_full.pth --lr 3e-4).
    Runs unchanged under torchrun (one process per CPU share or GPU); rank 0 reports and writes --out.
    """
    import dataclasses

    from pose_io.errors import InputError
    from pose_io.outputs import check_number, check_output
    from retarget.training import distributed
    from retarget.training.config import TrainConfig
    from retarget.training.losses import ablation_config
    from retarget.training.run import train as run_training
    from retarget.training.state import EpochProgress
    from retarget.world import CameraSpread

    check_output(out, "--out", overwrite=True)  # rewritten after every epoch; --resume continues it
    if out.exists() and not resume:
        raise InputError(f"--out {out}: already exists; pass --resume to continue it or choose another --out")
    if best is not None:
        check_output(best, "--best", overwrite=resume)  # a resumed run goes on improving it
        if best.resolve() == out.resolve():
            raise InputError(f"--best {best}: is --out; choose another file")
    if average is not None:
        check_output(average, "--average", overwrite=resume)
        if average.resolve() in {out.resolve(), best.resolve() if best is not None else None}:
            raise InputError(f"--average {average}: is --out or --best; choose another file")
    check_number("--average-from", average_from, 1, MAX_EPOCHS)
    if average is None and average_from is not None:
        raise InputError("--average-from: needs --average (the file the mean goes to)")
    check_number("--minutes", minutes, 0, MAX_MINUTES, low_open=True)
    check_number("--epochs", epochs, 1, MAX_EPOCHS)
    check_number("--batch-size", batch_size, 1, MAX_BATCH)
    check_number("--workers", workers, 0, MAX_WORKERS)
    check_number("--threads", threads, 1, MAX_THREADS)
    check_number("--extra-characters", extra_characters, 0, MAX_EXTRA_CHARACTERS)
    check_number("--extra-spread", extra_spread, 0.1, 4.0)
    check_number("--max-pitch", max_pitch, 0, 60)
    check_number("--perspective", perspective, 0, 1)
    check_number("--frontal-share", frontal_share, 0, 1)
    check_number("--turn-share", turn_share, 0, 1)
    check_number("--splice-share", splice_share, 0, 1)
    check_number("--bend", bend, 0, 45)
    check_number("--source-balance", source_balance, 0, 1)
    if not mocap.is_dir():
        raise InputError(f"--mocap {mocap}: no such folder")
    try:
        loss = dataclasses.replace(
            ablation_config(ablation.value), trajectory_weight=trajectory_weight, foot_weight=foot_weight,
            triplet_weight=triplet_weight, triplet_margin=triplet_margin, spread_weight=spread_weight,
            cycle_weight=cycle_weight, skeleton_ratio_weight=skeleton_ratio_weight,
            skeleton_cluster_weight=skeleton_cluster_weight,
            skeleton_cluster_ratio=skeleton_cluster_ratio, skeleton_proportion_weight=skeleton_proportion_weight,
        )
        config = TrainConfig(variant=variant.value, loss=loss, seed=seed, lr=lr, batch_size=batch_size,
                             extra_characters=extra_characters, extra_spread=extra_spread,
                             cameras=CameraSpread(max_pitch=max_pitch, perspective=perspective),
                             frontal_share=frontal_share, turn_share=turn_share, splice_share=splice_share,
                             bend_deg=bend, source_balance=source_balance)
    except ValueError as exc:
        raise InputError(str(exc)) from None
    dev = training_device(device, threads)
    # the bar is transient: an error ends as its one line; the summary below says where the run ended
    with distributed.launched(dev) as dev, \
            progress_bar("epoch 1", elapsed=True, remaining=False, enabled=distributed.current().is_main) as bar:

        def update(p: EpochProgress) -> None:
            shown = {k: v for k, v in p.losses.items() if k not in ("epoch", "seconds")}
            if p.step == p.steps_per_epoch and "epoch" in p.losses:  # the epoch's record
                shown = {k: v for k, v in shown.items() if k.startswith("val_")} or shown
            text = " ".join(f"{k}={v:.3f}" for k, v in shown.items())
            bar(p.step, p.steps_per_epoch, text=text, label=f"epoch {p.epoch}")

        summary = run_training(
            mocap, out, cache_dir=cache, real_dir=real, config=config, device=dev, epochs=epochs,
            minutes=minutes, resume=resume, num_workers=workers, init=init, progress=update, amp=amp,
            best=best, average=average, average_from=average_from,
        )
        main = distributed.current().is_main
    why = "time budget used up" if summary.stopped == "time" else "all epochs done"
    if main:
        console.print(f"wrote {summary.checkpoint} ({summary.epochs} epochs, {summary.steps} steps; {why})")
        if best is not None and summary.best_epoch is not None:
            console.print(f"wrote {best}: the weights of epoch {summary.best_epoch}, the lowest validation "
                          "retargeting error of the run")
        elif best is not None:
            console.print(f"--best {best}: no epoch of this call beat the run's earlier ones; not written")
        if average is not None and summary.averaged_epochs:
            console.print(f"wrote {average}: the mean of the weights of the run's epochs up to {summary.epochs}")
        elif average is not None:
            console.print(f"--average {average}: no epoch of this call entered the mean; not written")
