"""`clone pose`: inspect, draw, convert and extract 2D pose tracks.

Pose libraries (numpy, OpenCV, imageio-ffmpeg, MediaPipe) are imported inside the commands so that
`clone --help` stays fast.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer
from rich.console import Console

from clone.cli.choices import Layout, OutputFormat, PoseFormat
from clone.cli.common import console, user_errors
from clone.cli.progress import progress_bar
from pose_io.limits import MAX_FPS  # one limit for the library and the options

if TYPE_CHECKING:
    from pose_io.summary import TrackSummary

pose_app = typer.Typer(
    help="Inspect, draw, convert and extract 2D pose tracks (OpenPose JSON, COCO/AlphaPose JSON, npz, npy, csv).",
    no_args_is_help=True,
)

MAX_GAP = 100_000
MAX_SIGMA = 10_000.0

_FORMAT_HELP = "Input format (default: from the path)."
_PERSON_HELP = "Follow person K of the first frame with people (default: the most prominent one)."
_SIZE_HELP = "Image size WxH of the input (OpenPose/COCO/AlphaPose JSON store none; default: from the data)."
_IN_FPS_HELP = "Frame rate of the input (default: the file's, else 30)."


def _read(poses: Path, fmt: PoseFormat | None, person: int | None, size: str | None,
          in_fps: float | None, frames_size: tuple[int, int] | None = None) -> TrackSummary:
    """Read a track with the common reader options; ``frames_size`` stands in for a size the file lacks."""
    from pose_io.outputs import check_number
    from pose_io.readers import parse_size, read_track_summary

    check_number("--in-fps", in_fps, 0, MAX_FPS, low_open=True)
    image_size = parse_size(size) if size else None
    return read_track_summary(poses, fmt.value if fmt is not None else None, person=person, fps=in_fps, image_size=image_size,
                              fallback_size=frames_size)


@pose_app.command("info")
@user_errors
def info(
    poses: Annotated[Path, typer.Argument(help="Pose file or folder.")],
    fmt: Annotated[PoseFormat | None, typer.Option("--format", parser=PoseFormat, help=_FORMAT_HELP)] = None,
    person: Annotated[int | None, typer.Option("--person", min=0, help=_PERSON_HELP)] = None,
    size: Annotated[str | None, typer.Option("--size", help=_SIZE_HELP)] = None,
    in_fps: Annotated[float | None, typer.Option("--in-fps", help=_IN_FPS_HELP)] = None,
) -> None:
    """Frames, fps, image size, layout, people per frame and the missing share of every joint."""
    import numpy as np
    from rich.table import Table

    summary = _read(poses, fmt, person, size, in_fps)
    track = summary.track
    out = Console()
    w, h = track.image_size
    fps_note = {"given": "given", "file": "from the file", "default": "default; the file stores none"}
    size_note = {"given": "given", "file": "from the file", "fallback": "from the frames",
                 "inferred": "inferred from the data; set it with --size WxH"}
    counts = np.bincount(summary.people_counts)
    people = ", ".join(f"{n} {'person' if n == 1 else 'people'}: {c} frame{'' if c == 1 else 's'}"
                       for n, c in enumerate(counts) if c)
    lines = [
        ("file", f"{poses} ({summary.format})"),
        ("frames", f"{track.num_frames} ({track.num_frames / track.fps:.2f} s)"),
        ("fps", f"{track.fps:g} ({fps_note[summary.fps_source]})"),
        ("image size", f"{w}x{h} ({size_note[summary.size_source]})"),
        ("layout", f"{track.layout} ({len(track.joint_layout)} joints)"),
        ("people", people),
        ("followed", f"from frame {summary.start}; not found in {len(summary.lost)} frames with people"
         + (f" (first {summary.lost[0]})" if summary.lost else "")),
        ("missing", (f"{track.missing.mean():.1%} of joint-frames; "
                     f"{int(track.missing.all(axis=1).sum())} frames without any joint")),
        ("outliers", (f"{summary.outliers} joint{'' if summary.outliers == 1 else 's'} far outside the image and "
                      "body, read as missing")),
    ]
    for key, value in lines:
        out.print(f"[bold]{key:<11}[/bold]{value}", highlight=False)
    table = Table(title="missing joints", title_justify="left")
    table.add_column("joint")
    table.add_column("missing frames", justify="right")
    table.add_column("share", justify="right")
    table.add_column("mean confidence", justify="right")
    missing = track.missing.sum(axis=0)
    for j, name in enumerate(track.joint_layout.joints):
        seen = ~track.missing[:, j]
        mean_conf = f"{track.confidence[seen, j].mean():.2f}" if seen.any() else "-"
        table.add_row(name, str(int(missing[j])), f"{missing[j] / track.num_frames:.1%}", mean_conf)
    out.print(table)


@pose_app.command("show")
@user_errors
def show(
    poses: Annotated[Path, typer.Argument(help="Pose file or folder.")],
    out: Annotated[Path, typer.Option("--out", help="Output .mp4.")],
    frames: Annotated[Path | None, typer.Option(
        "--frames", help="Video or image folder to draw on (its size is the output size).")] = None,
    fmt: Annotated[PoseFormat | None, typer.Option("--format", parser=PoseFormat, help=_FORMAT_HELP)] = None,
    person: Annotated[int | None, typer.Option("--person", min=0, help=_PERSON_HELP)] = None,
    size: Annotated[str | None, typer.Option("--size", help=_SIZE_HELP + " With --frames: theirs.")] = None,
    in_fps: Annotated[float | None, typer.Option("--in-fps", help=_IN_FPS_HELP)] = None,
    overwrite: Annotated[bool, typer.Option("--overwrite", help="Replace an existing --out.")] = False,
) -> None:
    """Draw the skeleton over black or over the --frames video/folder into an H.264 mp4."""
    from pose_io.outputs import check_number, check_output
    from pose_io.video import read_frames
    from pose_io.video_out import write_pose_video

    check_output(out, "--out", suffixes=(".mp4",), overwrite=overwrite)
    check_number("--in-fps", in_fps, 0, MAX_FPS, low_open=True)
    background = read_frames(frames) if frames is not None else None
    summary = _read(poses, fmt, person, size, in_fps, frames_size=background.size if background else None)
    track = summary.track
    if background is not None and background.num_frames != track.num_frames:
        console.print(f"note: {frames} has {background.num_frames} frames, the poses {track.num_frames}",
                      highlight=False)
    with progress_bar("drawing") as update:
        write_pose_video(track, out, background=background, overwrite=overwrite, progress=update)
    w, h = background.size if background is not None else track.image_size
    typer.echo(f"wrote {out} ({track.num_frames} frames, {w}x{h}, {track.fps:g} fps)")


@pose_app.command("convert")
@user_errors
def convert(
    src: Annotated[Path, typer.Argument(metavar="IN", help="Pose file or folder.")],
    dst: Annotated[Path, typer.Argument(metavar="OUT", help="Output: folder (OpenPose JSON), .npz or .csv.")],
    to_layout: Annotated[Layout | None, typer.Option(
        "--to-layout", parser=Layout, help="Joint layout of the output (default: the input's).")] = None,
    fill_gaps: Annotated[int | None, typer.Option(
        "--fill-gaps", min=0, help="Interpolate gaps of up to N frames per joint.")] = None,
    smooth: Annotated[float | None, typer.Option(
        "--smooth", min=0.0, help="Confidence-weighted temporal Gaussian, SIGMA in frames.")] = None,
    fps: Annotated[float | None, typer.Option("--fps", help="Resample to this frame rate.")] = None,
    fmt: Annotated[PoseFormat | None, typer.Option("--format", parser=PoseFormat, help=_FORMAT_HELP)] = None,
    to: Annotated[OutputFormat | None, typer.Option(
        "--to", parser=OutputFormat, help="Output format (default: from OUT).")] = None,
    person: Annotated[int | None, typer.Option("--person", min=0, help=_PERSON_HELP)] = None,
    size: Annotated[str | None, typer.Option("--size", help=_SIZE_HELP)] = None,
    in_fps: Annotated[float | None, typer.Option("--in-fps", help=_IN_FPS_HELP)] = None,
    overwrite: Annotated[bool, typer.Option("--overwrite", help="Replace an existing OUT.")] = False,
) -> None:
    """Convert between pose formats; optionally fill gaps, smooth, resample and change the joint layout.

    Steps run in this order: fill gaps, smooth, resample, change layout (so derived joints like the neck profit).
    """
    from pose_io import clean
    from pose_io.errors import InputError
    from pose_io.outputs import FOLDER, check_number, check_output
    from pose_io.resample import resample
    from pose_io.writers import write_track

    kinds = {"openpose": (FOLDER,), "npz": (".npz",), "csv": (".csv",)}
    suffixes = kinds.get(to.value, None) if to is not None else (FOLDER, ".npz", ".csv")
    check_output(dst, "OUT", suffixes=suffixes, overwrite=overwrite)
    check_number("--fill-gaps", fill_gaps, 0, MAX_GAP)
    check_number("--smooth", smooth, 0, MAX_SIGMA)
    check_number("--fps", fps, 0, MAX_FPS, low_open=True)
    check_number("--in-fps", in_fps, 0, MAX_FPS, low_open=True)
    track = _read(src, fmt, person, size, in_fps).track
    if fill_gaps is not None:
        track, report = clean.fill_gaps(track, fill_gaps)
        console.print(report.summary(), highlight=False)
    if smooth:
        track = clean.smooth(track, smooth)
    if fps is not None:
        track = resample(track, fps)
    if to_layout is not None:
        track = track.to_layout(to_layout.value)
    if track.missing.all():  # the input had joints (the reader checked): the steps above lost them all
        steps = [f"--fps {fps:g} keeps {track.num_frames} frame(s)" if fps is not None else "",
                 f"--to-layout {to_layout.value}" if to_layout is not None else ""]
        raise InputError(f"{dst}: nothing to write: no frame of the result shows a joint "
                         f"({'; '.join(s for s in steps if s) or 'after cleaning'})")
    write_track(track, dst, fmt=to.value if to is not None else None, overwrite=overwrite)
    typer.echo(f"wrote {dst} ({track.num_frames} frames, {track.layout}, {track.fps:g} fps, "
               f"{track.image_size[0]}x{track.image_size[1]})")


@pose_app.command("extract")
@user_errors
def extract(
    video: Annotated[Path, typer.Argument(help="Video file or image folder.")],
    out: Annotated[Path, typer.Option(
        "--out", help="Output folder: gets poses/ (OpenPose BODY_25 JSON) and frames/.")],
    min_visibility: Annotated[float, typer.Option(
        "--min-visibility", min=0.0, max=1.0, help="Landmarks with lower MediaPipe visibility are missing.")] = 0.0,
    overwrite: Annotated[bool, typer.Option("--overwrite", help="Replace an existing --out.")] = False,
) -> None:
    """Extract poses with MediaPipe Pose (model complexity 1, tracking mode, every frame)."""
    from pose_io.errors import InputError
    from pose_io.outputs import FOLDER, check_output

    check_output(out, "--out", suffixes=(FOLDER,), overwrite=overwrite)
    if not video.exists():
        raise InputError(f"{video}: no such video or image folder")
    from pose_io.extract import ExtractConfig, extract_video  # MediaPipe: only once the arguments are good
    with progress_bar("extracting") as update:
        result = extract_video(video, out, overwrite=overwrite, config=ExtractConfig(min_visibility=min_visibility),
                               progress=update)
    typer.echo(f"wrote {result.poses_dir} and {result.frames_dir} "
               f"(person found in {result.frames_with_person} of {result.track.num_frames} frames)")
