"""`clone report`: drive the reference with global scaling and with retargeting, measure both, write a page.

torch, OpenCV and matplotlib are imported inside the command so that `clone --help` stays fast.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from clone.cli.choices import StageMode
from clone.cli.common import (
    DEVICE_HELP,
    MAX_REFINE_STEPS,
    AudioOption,
    RefineStepsOption,
    console,
    user_errors,
)
from clone.cli.progress import extract_if_video, progress_bar

# The primary pose measure first (with ground truth), as on the page; rows a run lacks are left out.
_HEADLINE = ("pose_rmse_pct", "root_rmse_pct", "facing_share", "ssim_crop", "ssim", "psnr_background",
             "consistency_pck", "flicker_ratio", "limb_error_pct", "foot_slide_pct", "jitter_pct", "stage_share")


@user_errors
def report_command(
    drive_poses: Annotated[Path, typer.Argument(
        help="The driver: a video (poses extracted once, then cached) or its poses (any format `clone pose` reads).")],
    out: Annotated[
        Path, typer.Option("--out", help="Report folder to write (report.html, video, plots, metrics.json).")
    ],
    model: Annotated[Path, typer.Option("--model", help="Reference model from `clone train-ref`.")] = Path(
        "ref_model.pt"
    ),
    gt_poses: Annotated[
        Path | None,
        typer.Option("--gt-poses", help="Poses of the reference really performing the driver's motion, frame for frame."),
    ] = None,
    gt_frames: Annotated[
        Path | None,
        typer.Option("--gt-frames", help="Frames (video or image folder) of the same, at the reference's frame size."),
    ] = None,
    overwrite: Annotated[bool, typer.Option("--overwrite", help="Replace an existing report folder.")] = False,
    device: Annotated[str, typer.Option("--device", help=DEVICE_HELP)] = "auto",
    weights: Annotated[
        Path | None,
        typer.Option(
            "--weights", help="Retargeting weights (default: the shipped ones, else those the model was made with)."
        ),
    ] = None,
    stage: Annotated[
        StageMode,
        typer.Option(
            "--stage", parser=StageMode,
            help="frame: anywhere in the picture, the driver's travel kept; reference: on the part of the "
            "frame the reference stood on; raw: as each method left them.",
        ),
    ] = StageMode.FRAME,
    refine_steps: RefineStepsOption = None,
    audio: AudioOption = "auto",
    consistency: Annotated[bool | None, typer.Option(
        "--consistency/--no-consistency", help="Run MediaPipe on every generated frame and measure whether it "
        "shows the pose it was made from (default when MediaPipe is installed; about 20 ms a frame and method "
        "on a CPU).")] = None,
) -> None:
    """Compare global scaling and retargeting on one driver: side-by-side video, measures, plots, one page."""
    from rich.table import Table

    from clone.metrics import METRICS
    from clone.report import REPORT_METHODS, make_report
    from pose_io.errors import InputError
    from pose_io.outputs import FOLDER, check_number, check_output
    from retarget.runtime import configure_threads, resolve_device

    check_output(out, "--out", suffixes=(FOLDER,), overwrite=overwrite)
    check_number("--refine-steps", refine_steps, 0, MAX_REFINE_STEPS)
    for name, path in (("DRIVE_POSES", drive_poses), ("--model", model), ("--gt-poses", gt_poses),
                       ("--gt-frames", gt_frames), ("--weights", weights)):
        if path is not None and not path.exists():
            raise InputError(f"{name} {path}: no such file or folder")
    try:
        dev = str(resolve_device(device))
    except ValueError as exc:
        raise InputError(str(exc)) from None
    configure_threads()
    extract_if_video(drive_poses)
    with progress_bar("report") as bar:
        run = make_report(
            drive_poses, out, model_path=model, gt_poses=gt_poses, gt_frames=gt_frames, overwrite=overwrite,
            device=dev, weights=weights, progress=bar,
            stage=stage.value, refine_steps=refine_steps, audio=audio, consistency=consistency,
        )  # fmt: skip
    table = Table(title=f"{run.frames} frames, {run.seconds:.0f} s")
    table.add_column("measure")
    for name in run.summary:
        table.add_column(REPORT_METHODS[name][0], justify="right")
    for key in _HEADLINE:
        if all(key in s for s in run.summary.values()):
            info = METRICS[key]
            values = [f"{s[key] * info.scale:.4g}" for s in run.summary.values()]
            table.add_row(f"{info.label} ({info.unit})" if info.unit else info.label, *values)
    console.print(table)
    if run.coverage_line is not None:
        console.print(run.coverage_line)
    typer.echo(f"wrote {run.page}")
