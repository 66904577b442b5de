"""`clone synth`: synthetic performers of the motion world.

``clone synth render`` replays a motion-capture clip on a character and renders it from a view: frames,
the exact projected BODY_25 poses and a meta file. Rendering the reference character with the driver's
motion and the reference's view gives the ground truth of a cloning run. ``clone synth characters``
lists the named characters.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from clone.cli.common import user_errors
from clone.cli.progress import progress_bar

_SLEEVES = {"long": "long-sleeved", "short": "short-sleeved", "none": "sleeveless"}

synth_app = typer.Typer(
    help="Synthetic performers: render a motion on a character; list the characters.", no_args_is_help=True
)


@synth_app.command("render")
@user_errors
def render_command(
    motion: Annotated[Path, typer.Argument(help="Motion file: BVH (.bvh, .bvh.gz) or Acclaim AMC.")],
    out: Annotated[Path, typer.Option("--out", help="Output folder (frames/, poses/, poses.npz, meta.json).")],
    character: Annotated[str, typer.Option("--character", help="Named character or an integer seed.")] = "average",
    yaw: Annotated[
        float, typer.Option("--yaw", help="View yaw in degrees (0 front, +90 the character's left).")
    ] = 0.0,
    pitch: Annotated[float, typer.Option("--pitch", help="Camera elevation in degrees (+ from above).")] = 0.0,
    size: Annotated[int, typer.Option("--size", help="Square canvas side in pixels.")] = 256,
    start: Annotated[int, typer.Option("--start", help="First frame (after resampling to --fps).")] = 0,
    frames: Annotated[int | None, typer.Option("--frames", help="Number of frames (default: to the end).")] = None,
    fps: Annotated[float, typer.Option("--fps", help="Frame rate the motion is resampled to.")] = 30.0,
    overwrite: Annotated[bool, typer.Option("--overwrite", help="Replace an existing --out folder.")] = False,
) -> None:
    """Render MOTION performed by a character, framed by the world's framing rule."""

    from clone.synth import get_character, save_performance
    from pose_io.errors import InputError
    from pose_io.outputs import FOLDER, check_number, check_output
    from retarget.world.rigs import load_motion

    check_output(out, "--out", suffixes=(FOLDER,), overwrite=overwrite)
    check_number("--size", size, 16, 4096)
    check_number("--yaw", yaw, -3600.0, 3600.0)
    check_number("--pitch", pitch, -89.0, 89.0)
    check_number("--start", start, 0)
    check_number("--frames", frames, 1, 1_000_000)
    check_number("--fps", fps, 0, 1000.0, low_open=True)
    if not motion.is_file():
        raise InputError(f"{motion}: no such motion file")
    try:
        skeleton, look, seed = get_character(character)
    except InputError:
        raise
    except ValueError as exc:  # a negative seed reaches numpy's SeedSequence
        raise InputError(f"--character {character!r}: {exc}; give a name or a seed >= 0") from None
    clip = load_motion(motion, fps=fps)
    if not 0 <= start < clip.num_frames:
        raise InputError(f"{motion}: --start {start} is outside its {clip.num_frames} frames at {fps:g} fps")
    if frames is not None and not 1 <= frames <= clip.num_frames - start:
        raise InputError(f"{motion}: --frames {frames} does not fit: {clip.num_frames - start} frames from --start {start}")
    count = (clip.num_frames - start) if frames is None else frames
    extra = {"character": {"requested": character, "seed": seed}}
    with progress_bar(f"rendering {clip.name}") as bar:
        save_performance(out, clip, skeleton, look, yaw, pitch, size, start, frames, overwrite=overwrite,
                         extra_meta=extra, on_frame=lambda t: bar(t + 1, count))
    typer.echo(f"wrote {out} ({count} frames, {size}x{size}, {skeleton.name} as {look.name})")


@synth_app.command("characters")
@user_errors
def characters_command() -> None:
    """List the named characters: height, proportions and look."""
    from clone.synth.appearance import get_character
    from retarget.world.characters import NAMED_CHARACTERS

    for name in NAMED_CHARACTERS:
        skeleton, look, _ = get_character(name)
        d = skeleton.as_dict()
        arm = d["l_elbow"] + d["l_wrist"]
        typer.echo(
            f"{name:<16} height {skeleton.height:.2f} m  legs {skeleton.leg_length:.2f} m "
            f"({skeleton.leg_length / skeleton.height:.2f} H)  torso {d['neck']:.2f} m  arms {arm:.2f} m  "
            f"shoulders {d['l_shoulder'] + d['r_shoulder']:.2f} m  | {_SLEEVES[look.sleeves]} {look.pattern} top, "
            f"{look.bottom_style}, {look.hair_style} hair"
        )
    typer.echo("or any integer seed: a sampled skeleton and look")
