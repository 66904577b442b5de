"""`clone train-ref`, `clone drive` and `clone strip`: performance cloning with a pose-to-frame generator.

    clone train-ref ref_poses/ frames/          # writes ./ref_model.pt (+ ref_model.preview.png)
    clone drive drive_poses/ --out out.mp4      # reads ./ref_model.pt
    clone strip ref_model.pt --out small.pt     # the same model without its resume state, to drive elsewhere

torch and the video libraries are imported inside the commands so that `clone --help` stays fast.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from clone.cli.choices import Align, CanvasMode, Method, StageMode
from clone.cli.common import (
    DEVICE_HELP,
    MAX_REFINE_STEPS,
    MAX_THREADS,
    AudioOption,
    RefineStepsOption,
    console,
    resolve_device_option,
    training_device,
    user_errors,
)
from clone.cli.progress import extract_if_video, progress_bar, training_progress
from pose_io.errors import InputError

DEFAULT_MODEL = Path("ref_model.pt")
DEFAULT_SIZE = 128
# Ranges of the options that scale memory, disk or time (checked before any work; the disk is shared).
# 16 passes default_depth but its discriminator bottoms out at 1x1, where instance norm fails.
MIN_SIZE, MAX_SIZE = 32, 1024
MAX_STEPS = 10_000_000
MAX_MINUTES = 7 * 24 * 60.0
MAX_BATCH = 4096
MAX_GAP = 100_000


@user_errors
def train_ref(
    ref_poses: Annotated[Path, typer.Argument(
        help="The reference: its video (poses extracted once, then cached), or its poses in any track "
        "`clone pose` reads.")],
    frames: Annotated[Path | None, typer.Argument(
        help="The reference's frames: a video or a folder of images (default: REF_POSES when it is a video).")
    ] = None,
    out: Annotated[Path, typer.Option("--out", "-o", help="Reference model to write.")] = DEFAULT_MODEL,
    size: Annotated[int | None, typer.Option(
        "--size", help=f"Canvas size: 128, 256 or 512 (any power of two from {MIN_SIZE} to {MAX_SIZE}). "
        f"Default {DEFAULT_SIZE}.")] = None,
    steps: Annotated[int | None, typer.Option(
        "--steps", help="Stop when the model has this many steps in total (default 2000 without --minutes).")] = None,
    minutes: Annotated[float | None, typer.Option("--minutes", help="Stop after this many minutes.")] = None,
    batch_size: Annotated[int | None, typer.Option(
        "--batch-size", min=1, help="Samples per step over all processes (under torchrun each takes its share; "
        "the learning rate is that of one process). Default one per process; when resuming, the stored one.")] = None,
    canvas: Annotated[CanvasMode, typer.Option(
        "--canvas", parser=CanvasMode, help="crop: around the performer; full: the letterboxed frame.")
    ] = CanvasMode.CROP,
    device: Annotated[str, typer.Option("--device", help=DEVICE_HELP)] = "auto",
    threads: Annotated[int | None, typer.Option("--threads", min=1, help="CPU threads (default: free cores).")] = None,
    resume: Annotated[bool, typer.Option(
        "--resume", help="Continue training the model at --out from the training state stored in it.")] = False,
    overwrite: Annotated[bool, typer.Option("--overwrite", help="Replace an existing model at --out.")] = False,
    init: Annotated[str | None, typer.Option(
        "--init", help="Start the new model from the generator (and discriminator, face pass) of this model "
        "file, trained on anyone with the same --size and options, or a `clone train-prior` prior; none: random "
        "weights. Default: the shipped generator prior where it fits (--size 256 with the default options), "
        "else random weights.")] = None,
    align: Annotated[Align, typer.Option(
        "--align", parser=Align, help="exact: frame and pose counts must agree; trim: use the common prefix.")
    ] = Align.EXACT,
    weights: Annotated[Path | None, typer.Option(
        "--weights", help="Retargeting weights for the reference's codes (default: the shipped ones).")] = None,
    amp: Annotated[bool | None, typer.Option(
        "--amp/--no-amp", help="bfloat16 mixed precision (default: on where the GPU supports it; on the "
        "CPU only with --amp, where it has bfloat16 instructions: 1.6x the steps, less quality per minute).")] = None,
    background: Annotated[bool | None, typer.Option(
        "--background/--no-background", help="Estimate the static background from the frames and let the "
        "generator composite the person over it (default; for a static camera). When resuming, the stored "
        "choice.")] = None,
    details: Annotated[bool | None, typer.Option(
        "--details/--no-details", help="Pose maps with the face, hands and feet the poses carry, the face drawn "
        "only from the front (default); --no-details: the body15 skeleton alone. When resuming, the stored "
        "choice.")] = None,
    face_pass: Annotated[bool | None, typer.Option(
        "--face-pass/--no-face-pass", help="Train a face pass beside the generator: a small network on the face's "
        "crop that sharpens it, run by `clone drive` (default from --size 128 up, with detailed pose maps). "
        "Measured at 10 minutes on a real reference: face SSIM 0.876 against 0.692, the person's box 0.915 "
        "against 0.910. When resuming, the stored choice.")] = None,
    exemplars: Annotated[bool | None, typer.Option(
        "--exemplars/--no-exemplars", help="Give the generator, for each frame, the reference's own frame "
        "nearest in pose laid onto the pose (the head by its face points) to copy the clothes' and the face's "
        "detail from; the frames it comes from are stored in the model (default from --size 128 up). "
        "Measured at 3 minutes on real references: at 256² person box SSIM 0.885 and 0.926 against 0.868 and "
        "0.909, face 0.855 and 0.870 against 0.802 and 0.824; at 128² 0.928 against 0.892. When resuming, the "
        "stored choice.")] = None,
    face_gan: Annotated[float | None, typer.Option(
        "--face-gan", min=0.0, max=100.0, help="Weight of a second discriminator on the face (training only; "
        "detailed pose maps). Measured at 10 minutes on a real reference, without the face pass: face SSIM 0.768 "
        "against 0.692, the person's box 0.888 against 0.910 (a speckled texture on the clothes); the face pass "
        "alone reached 0.867 and 0.914. Default 0: off.")] = None,
) -> None:
    """Train a pose-to-frame generator on a reference video (frame t must match pose t).

    clone train-ref REF.mp4 takes poses and frames from the one video.

    Writes ONE model (default ./ref_model.pt, where `clone drive` looks for it).

    The model also holds its training state: --resume continues it exactly.

    Beside it: a preview image (pose | generated | real).

    An existing model is never replaced unless --resume or --overwrite is given.

    Runs unchanged under torchrun (one process per CPU share or GPU); rank 0 reports and writes the model.
    """

    from clone.model.reference import preview_path
    from clone.train_ref import LossConfig, TrainConfig, train_reference
    from pose_io.outputs import check_number, check_output
    from retarget.training import distributed

    if size is not None and not (MIN_SIZE <= size <= MAX_SIZE and size & (size - 1) == 0):
        raise InputError(f"--size: must be a power of two from {MIN_SIZE} to {MAX_SIZE}, got {size}")
    check_number("--steps", steps, 1, MAX_STEPS)
    check_number("--minutes", minutes, 0, MAX_MINUTES, low_open=True)
    check_number("--batch-size", batch_size, 1, MAX_BATCH)
    check_number("--threads", threads, 1, MAX_THREADS)
    # Every output is checked before the frames are read: the model, and the preview written beside it.
    check_output(out, "--out", overwrite=overwrite, replaceable=resume)
    check_output(preview_path(out), "--out (its preview)", suffixes=(".png",), overwrite=overwrite or resume)
    from pose_io.video_poses import is_video

    if frames is None:
        if not is_video(ref_poses):
            raise InputError(f"FRAMES: needed when REF_POSES is not a video ({ref_poses})")
        frames = ref_poses
    init_path = None if init is None or init.lower() == "none" else Path(init)
    if init is not None and init.lower() == "auto":
        raise InputError("--init auto: leave --init out for the shipped prior where it fits")
    if init_path is not None and resume:
        raise InputError("--init starts a new model; --resume continues one: pass only one of them")
    for name, path in (("REF_POSES", ref_poses), ("FRAMES", frames), ("--weights", weights), ("--init", init_path)):
        if path is not None and not path.exists():
            raise InputError(f"{name} {path}: no such file or folder")
    dev = training_device(device, threads)
    if face_gan and details is False:
        raise InputError("--face-gan needs the detailed pose maps (the face's points): drop --no-details")
    if face_pass and details is False:
        raise InputError("--face-pass needs the detailed pose maps (the face's points): drop --no-details")
    extract_if_video(ref_poses)  # under torchrun each process reads the same cache entry (atomic writes)
    if resume:
        # The stored run's settings apply; a --size given must match it. A --batch-size given replaces the
        # stored one (e.g. to resume on more processes than the stored batch has samples).
        config = None
        if face_gan is not None:
            raise InputError("--face-gan: a resumed model keeps the losses it was trained with")
        if size is not None or batch_size is not None or background is not None or details is not None \
                or face_pass is not None or exemplars is not None:
            from clone.train_ref import load_resumable

            stored = load_resumable(out).training["config"]
            if background is not None and background != bool(stored.get("background", False)):
                raise InputError(f"--{'' if background else 'no-'}background: the model was trained "
                                 f"{'without' if background else 'with'} a background plate; cannot resume so")
            stored_details = stored.get("pose_layout", "body15") == "body31"
            if details is not None and details != stored_details:
                raise InputError(f"--{'' if details else 'no-'}details: the model's pose maps are "
                                 f"{'detailed' if stored_details else 'body15 alone'}; cannot resume so")
            stored_pass = bool(stored.get("face_pass", False))
            if face_pass is not None and face_pass != stored_pass:
                raise InputError(f"--{'' if face_pass else 'no-'}face-pass: the model was trained "
                                 f"{'with' if stored_pass else 'without'} a face pass; cannot resume so")
            stored_exemplars = bool(stored.get("exemplar", False))
            if exemplars is not None and exemplars != stored_exemplars:
                raise InputError(f"--{'' if exemplars else 'no-'}exemplars: the model was trained "
                                 f"{'with' if stored_exemplars else 'without'} exemplars; cannot resume so")
            config = TrainConfig(size=size if size is not None else int(stored["size"]),
                                 batch_size=batch_size if batch_size is not None else int(stored["batch_size"]))
    else:
        launched_world = distributed.from_environment()  # under torchrun: one sample per process by default
        per_process = launched_world.size if launched_world is not None else 1
        config = TrainConfig(size=size or DEFAULT_SIZE, canvas_mode=canvas.value, batch_size=batch_size or per_process,
                             background=background is not False,
                             pose_layout="body15" if details is False else "body31",
                             face_pass=False if details is False else face_pass, exemplar=exemplars,
                             loss=LossConfig(face_gan=face_gan or 0.0))
        if init is None:
            from clone.train_ref.prior import matching_prior

            init_path = matching_prior(config)
            if init_path is not None:
                console.print("starting from the shipped generator prior (--init none: random weights)")

    with distributed.launched(dev) as dev, \
            progress_bar("train-ref", count=False, elapsed=True, enabled=distributed.current().is_main) as bar:

        update = training_progress(bar, {"reading": "reading frames"})

        result = train_reference(
            ref_poses, frames, out, config=config, steps=steps, minutes=minutes, device=dev, resume=resume,
            overwrite=overwrite, align=align.value, weights=weights, progress=update, amp=amp,
            grow_threads=threads is None, init=init_path,
        )
        main = distributed.current().is_main
    if not main:  # rank 0 reports
        return
    skipped = f", {result.skipped_frames} skipped (no usable pose)" if result.skipped_frames else ""
    codes = "with retargeting codes" if result.has_codes else "without retargeting codes (drive with --weights)"
    state = " (interrupted)" if result.interrupted else ""
    console.print(f"trained {result.steps_this_run} steps (total {result.steps}) in {result.seconds:.0f} s on "
                  f"{result.usable_frames} frames{skipped}{state}")
    console.print(f"wrote {result.model_path} {codes}; preview {result.preview_path}")
    _prepare_drive(result.model_path)


def _prepare_drive(model_path: Path) -> None:
    """Quantise the new generator for `clone drive` now (int8 ONNX Runtime, into its cache), so that the first
    drive of the model runs at the cached speed; nothing to do without the `fast` extra."""
    from clone.runtime.onnx import onnx_available

    if not onnx_available():
        return
    from clone.model.reference import load_reference_model
    from clone.runtime.int8 import build_int8_generator

    with console.status("quantising the generator to int8 for clone drive"):
        generator = build_int8_generator(load_reference_model(model_path))
    if generator.precision == "int8":
        console.print("int8 generator for clone drive cached")


@user_errors
def drive(
    drive_poses: Annotated[Path, typer.Argument(
        help="The driver: a video (poses extracted once, then cached) or its poses in any track `clone pose` "
        "reads.")],
    out: Annotated[Path, typer.Option("--out", "-o", help="Video to write (.mp4, H.264).")],
    model: Annotated[Path, typer.Option(
        "--model", "-m", help="Reference model from `clone train-ref`.")] = DEFAULT_MODEL,
    method: Annotated[Method, typer.Option(
        "--method", parser=Method,
        help="retarget: the network; global-scale: Everybody Dance Now's scaling; none: the driver's pixels.")
    ] = Method.RETARGET,
    stage: Annotated[StageMode, typer.Option(
        "--stage", parser=StageMode,
        help="frame: anywhere in the picture, the driver's travel kept; reference: on the part of the "
        "frame the reference stood on; raw: as the method left them.")
    ] = StageMode.FRAME,
    poses_out: Annotated[Path | None, typer.Option(
        "--poses-out", help="Also write the driven poses: a folder (OpenPose JSON), .npz or .csv.")] = None,
    side_by_side: Annotated[bool, typer.Option(
        "--side-by-side", help="Frames show driver skeleton | driven skeleton | result.")] = False,
    device: Annotated[str, typer.Option("--device", help=DEVICE_HELP)] = "auto",
    threads: Annotated[int | None, typer.Option("--threads", min=1, help="CPU threads (default: free cores).")] = None,
    weights: Annotated[Path | None, typer.Option(
        "--weights", help="Retargeting weights (default: those the model's codes came from, else shipped).")] = None,
    max_gap: Annotated[int, typer.Option(
        "--max-gap", min=0, help="Fill gaps of up to this many frames in the driver.")] = 5,
    overwrite: Annotated[bool, typer.Option("--overwrite", help="Replace existing outputs.")] = False,
    runtime: Annotated[str, typer.Option(
        "--runtime", help="The generator's runtime: int8: ONNX Runtime quantised, about 2x onnx at 256², SSIM "
        "0.003 lower on the demo, ~3 s to quantise once per model (then cached); onnx: ONNX Runtime fp32, "
        "1.5-1.8x torch, same frames; torch: PyTorch, also on GPUs; auto: int8 on a CPU with the `fast` extra, "
        "else torch.")] = "auto",
    foot_lock: Annotated[bool, typer.Option(
        "--foot-lock/--no-foot-lock",
        help="--method retarget: hold the feet still while the driver's feet touch the ground (moves the body "
        "against the slide, then the ankles, knees re-solved; removes foot skating at the same pose error).")
    ] = True,
    refine_steps: RefineStepsOption = None,
    audio: AudioOption = "auto",
) -> None:
    """Make a video of the reference performing the driver's motion."""
    from clone.drive.run import drive as run_drive
    from pose_io.outputs import FOLDER, check_number, check_output

    check_number("--threads", threads, 1, MAX_THREADS)
    check_number("--max-gap", max_gap, 0, MAX_GAP)
    check_number("--refine-steps", refine_steps, 0, MAX_REFINE_STEPS)
    check_output(out, "--out", suffixes=(".mp4",), overwrite=overwrite)
    if poses_out is not None:
        check_output(poses_out, "--poses-out", suffixes=(FOLDER, ".npz", ".csv"), overwrite=overwrite)
        if poses_out.absolute() == out.absolute():
            raise InputError(f"--poses-out {poses_out}: the same path as --out")
    dev = resolve_device_option(device, threads)
    extract_if_video(drive_poses)
    with progress_bar("drive") as bar:
        result = run_drive(
            drive_poses, out, model_path=model, method=method.value, stage=stage.value, poses_out=poses_out,
            side_by_side=side_by_side, foot_lock=foot_lock, refine_steps=refine_steps,
            device=dev, weights=weights, overwrite=overwrite, max_gap=max_gap, runtime=runtime,
            progress=bar, audio=audio,
        )
    console.print(f"wrote {result.out}: {result.frames} frames {result.size[0]}x{result.size[1]} at "
                  f"{result.fps:g} fps ({result.method}, {result.seconds:.1f} s)"
                  + (f", with the sound of {result.audio}" if result.audio is not None else ""))
    if result.stage_share > 0:
        where = "in the picture" if stage is StageMode.FRAME else "on the reference's stage"
        console.print(f"kept {where}: {100 * result.stage_share:.1f}% of frames were outside it "
                      "(--stage raw keeps them there)")
    if result.poses_out is not None:
        console.print(f"wrote {result.poses_out}")
    line = result.coverage.line() if result.coverage is not None else None
    if line is not None:
        console.print(line)


@user_errors
def strip(
    model: Annotated[Path, typer.Argument(help="Reference model from `clone train-ref`.")],
    out: Annotated[Path, typer.Option("--out", "-o", help="The stripped model to write (.pt).")],
    overwrite: Annotated[bool, typer.Option(
        "--overwrite", help="Replace an existing --out (MODEL itself too: it then loses its resume state).")] = False,
) -> None:
    """Write MODEL without what only --resume reads (discriminator, optimisers, random state): it drives the same."""
    from clone.train_ref.checkpoint import write_stripped
    from pose_io.outputs import check_output

    check_output(out, "--out", suffixes=(".pt",), overwrite=overwrite)
    written, before, after = write_stripped(model, out, overwrite=overwrite)
    console.print(f"wrote {written}: {after / 2**20:.1f} MB (was {before / 2**20:.1f} MB); it drives as {model} "
                  "does and cannot be resumed")
