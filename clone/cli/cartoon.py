"""`clone cartoon`: a cartoon character of exaggerated proportions performs a driver's motion (paper Sec. 7).

Heavy libraries are imported inside the command so that `clone --help` stays fast.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from clone.cli.common import DEVICE_HELP, MAX_REFINE_STEPS, RefineStepsOption, console, user_errors
from clone.cli.progress import progress_bar

_CHARACTER_HELP = (
    "A preset (standard, bighead, stubby, longarms, chibi) or a JSON file of part factors on a standard body, "
    'e.g. {"name": "tiny legs", "legs": 0.5, "head": 1.5}.'
)


@user_errors
def cartoon_command(
    driver: Annotated[Path, typer.Argument(help="Driver's poses (OpenPose folder, COCO/AlphaPose JSON, npz, npy, csv).")],
    character: Annotated[str, typer.Option("--character", help=_CHARACTER_HELP)],
    out: Annotated[Path, typer.Option("--out", help="The cartoon video (.mp4), in the driver's frame size.")],
    yaw: Annotated[
        float | None,
        typer.Option("--yaw", min=-90.0, max=90.0,
                     help="View of the character in degrees (0 front, +90 its left side); default: the driver's."),
    ] = None,
    report: Annotated[
        Path | None, typer.Option("--report", help="Measures as JSON (default: next to the video, OUT with .json).")
    ] = None,
    poses: Annotated[
        Path | None, typer.Option("--poses", help="Also write the cartoon's body15 poses (.npz, .csv or a folder).")
    ] = None,
    weights: Annotated[
        Path | None,
        typer.Option("--weights", help="clone2d checkpoint, or the authors' pretrained_full.pth (default: shipped)."),
    ] = None,
    size: Annotated[
        str | None, typer.Option("--size", help="Image size WxH of a driver that stores none (OpenPose JSON).")
    ] = None,
    device: Annotated[str, typer.Option("--device", help=DEVICE_HELP)] = "auto",
    overwrite: Annotated[bool, typer.Option("--overwrite", help="Replace existing outputs.")] = False,
    refine_steps: RefineStepsOption = None,
) -> None:
    """Retarget DRIVER's motion onto a cartoon character, hold its proportions, draw it; report limb errors."""
    import json
    import time

    from clone.cartoon import cartoon_frames, load_character, make_cartoon, summary_lines
    from clone.drive.poses import load_driving_retargeter
    from pose_io.atomic import atomic_file
    from pose_io.errors import InputError
    from pose_io.outputs import FOLDER, check_number, check_output
    from pose_io.readers import parse_size, read_track
    from pose_io.video_out import VideoWriter
    from pose_io.writers import write_track
    from retarget.runtime import configure_threads

    start = time.perf_counter()
    check_output(out, "--out", suffixes=(".mp4",), overwrite=overwrite)
    check_number("--refine-steps", refine_steps, 0, MAX_REFINE_STEPS)
    report = report if report is not None else out.with_suffix(".json")
    check_output(report, "--report", suffixes=(".json",), overwrite=overwrite)
    if poses is not None:
        check_output(poses, "--poses", suffixes=(FOLDER, ".npz", ".csv"), overwrite=overwrite)
    named = [p.absolute() for p in (out, report, poses) if p is not None]
    if len(set(named)) != len(named):
        raise InputError("--out, --report and --poses must be different paths")
    spec = load_character(character)
    track = read_track(driver, image_size=parse_size(size) if size else None)
    configure_threads()
    retargeter = load_driving_retargeter(weights, device, refine_steps)
    cartoon = make_cartoon(track, spec, retargeter, yaw=yaw, name=str(driver))
    with progress_bar("drawing", remaining=False) as bar, \
            VideoWriter(out, track.fps, overwrite=overwrite) as video:
        for t, frame in enumerate(cartoon_frames(cartoon.track, cartoon.look)):
            video.write(frame)
            bar(t + 1, len(cartoon.track))
    if poses is not None:
        write_track(cartoon.track, poses, overwrite=overwrite)
    document = {**cartoon.report, "driver": str(driver), "video": str(out),
                "seconds": round(time.perf_counter() - start, 2)}
    with atomic_file(report, overwrite=overwrite) as tmp:
        tmp.write_text(json.dumps(document, indent=1) + "\n")
    for line in summary_lines(cartoon.report):
        console.print(line)
    written = ", ".join(str(p) for p in (out, report, poses) if p is not None)
    console.print(f"wrote {written} in {document['seconds']:.1f} s")

