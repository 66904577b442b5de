"""`clone retarget eval-cloning`: retargeting weights scored on the demo's pairs over a split's motions.

torch is imported inside the command so that `clone --help` stays fast.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer

from clone.cli.choices import Split
from clone.cli.common import (
    DEVICE_HELP,
    MAX_CLIP_FRAMES,
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

MAX_CLIPS = 100_000


@user_errors
def eval_cloning(
    mocap: MocapOption,
    out: Annotated[Path, typer.Option("--out", help="Folder to write: cloning.json, cloning.md.")],
    weights: OurWeightsOption = None,
    compare: CompareOption = None,
    split: Annotated[
        Split, typer.Option("--split", parser=Split, help="World split whose clips drive (tune on val).")
    ] = Split.VAL,
    clips: Annotated[int | None, typer.Option("--clips", help="Use at most this many clips (default: all).")] = None,
    frames: Annotated[int, typer.Option("--frames", help="Frames per case (the demo's: 100).")] = 100,
    world_seed: WorldSeedOption = 0,
    cache: WorldCacheOption = None,
    threads: Annotated[int | None, typer.Option("--threads", help="CPU threads (default: the free cores).")] = None,
    device: Annotated[str, typer.Option("--device", help=DEVICE_HELP)] = "auto",
    turns: Annotated[bool, typer.Option("--turns/--no-turns", help="Also a turning driver per clip: the child at "
                     "-30° turning its whole body by 90-360° during the case, its truth turning alike (kind "
                     "'turn', apart from 'all').")] = True,
    travelling: Annotated[bool, typer.Option("--travel/--no-travel", help="Also a travelling driver on every clip "
                          "that walks across: the child 50° from the reference's camera in a picture three times as "
                          "wide, turning on every other such clip (kind 'travel', apart from 'all').")] = True,
    overwrite: Annotated[bool, typer.Option("--overwrite", help="Replace an existing --out.")] = False,
) -> None:
    """Pose error and placement of retargeting weights on `clone demo`'s three pairs built from every clip of a split.

    Each usable clip of the split gives the demo's drivers (the child at +30°, the reference's own body at -30°,
    the child at -30°) and their ground truth (the demo's reference character at +30°), and a turning driver (the
    child at -30° turning by 90-360°; --no-turns leaves it out) and, on clips that walk across, a travelling
    driver in a wide picture (--no-travel leaves it out); every driver is moved onto the demo's reference track
    as `clone drive` does it. Global scaling is scored on the same cases.
    """

    from clone.demo import validation
    from pose_io.atomic import atomic_dir
    from pose_io.errors import InputError
    from pose_io.outputs import FOLDER, check_number, check_output
    from retarget.api import PACKAGED_WEIGHTS
    from retarget.runtime import configure_threads
    from retarget.world import MotionWorld

    check_output(out, "--out", suffixes=(FOLDER,), overwrite=overwrite)
    check_number("--clips", clips, 1, MAX_CLIPS)
    check_number("--frames", frames, 16, MAX_CLIP_FRAMES)
    check_number("--threads", threads, 1, MAX_THREADS)
    if not mocap.is_dir():
        raise InputError(f"--mocap {mocap}: no such folder")
    networks: dict[str, Path | None] = {"ours": weights}
    networks.update(named_checkpoints(compare, taken=("ours", "global scaling (EDN)")))
    configure_threads(threads)
    config = validation.DEMO
    references = validation.references(config)
    # Weights and device are checked before the world is built.
    methods = {name: validation.network_drive(path, references, device) for name, path in networks.items()}
    methods["global scaling (EDN)"] = validation.global_scale_drive(references)
    wide = validation.picture_size(config, validation.WIDE)
    world = MotionWorld.build(mocap, cache, seed=world_seed)
    cases = validation.cloning_cases(world.split(split.value).clips, mocap, frames, clips, config,
                                     world.config.fps, turns=turns, travelling=travelling)  # fmt: skip
    with progress_bar("eval-cloning") as bar:
        errors = validation.score(cases, methods, lambda done, _: bar(done, len(cases)))
    doc = validation.summarise(cases, errors, "ours")
    doc.update({
        "split": split.value, "frames": frames, "baseline": "ours",
        "weights": {name: str(path or PACKAGED_WEIGHTS) for name, path in networks.items()},
        "pairs": "; ".join([f"{p.name}: {p.character} at {p.yaw:+g}°" for p in config.pairs]
                           + ([(f"{validation.TURN_KIND}: {validation.TURN_CHARACTER} at {validation.TURN_YAW:+g}° "
                                "turning by 90-360° (apart from 'all')")] if turns else [])
                           + ([(f"{validation.TRAVEL_KIND}: {validation.TRAVEL_CHARACTER} at "
                                f"{validation.TRAVEL_YAW:+g}° walking across a {'x'.join(map(str, wide))} picture, "
                                "turning on every other clip (apart from 'all')")] if travelling else [])),
        "reference": f"{config.reference_character} performing the built-in {config.reference_motion!r} motion at "
                     f"{config.reference_yaw:+g}°, {len(references[validation.SQUARE])} frames",
        "case_list": [{"clip": c.clip, "kind": c.kind,
                       **{key: {n: float(e[k]) for n, e in rows.items()} for key, rows in errors.items()}}
                      for k, c in enumerate(cases)],
    })  # fmt: skip
    table = validation.markdown(doc)
    with atomic_dir(out, overwrite=overwrite) as tmp:
        (tmp / "cloning.json").write_text(json.dumps(doc, indent=2))
        (tmp / "cloning.md").write_text(table)
    typer.echo(table)
    console.print(f"wrote {out}: cloning.json, cloning.md ({doc['cases']} cases from {doc['clips']} clips)")
