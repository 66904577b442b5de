"""Driving a trained reference model with someone else's poses (`clone drive`).

1. Read the driver's track (any format ``pose_io`` reads), as body15, with short gaps filled.
2. Move it onto the reference (``--method``):
   - ``retarget``: the retargeting network, with the reference's skeleton and view codes stored in the model
     (recomputed from the stored reference track when other weights are given);
   - ``global-scale``: Everybody Dance Now's per-frame scale and translation between feet positions;
   - ``none``: the driver's pixel coordinates as they are, read as the reference's;
   then, for the first two, kept on the part of the frame the reference stood on (``--stage``, :mod:`clone.drive.stage`).
3. Draw each frame's pose map on the reference's canvas and run the generator frame after frame, each frame
   conditioned on the one it generated before (the first on zeros, as in training).
4. Write an H.264 mp4 at the driver's fps, one frame at a time: memory does not grow with the track.

Drawing, the generator and the encoder run side by side in threads (:mod:`clone.runtime.pipeline`).
"""

from __future__ import annotations

import logging
import os
import time
from collections.abc import Callable
from contextlib import closing
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from clone.choices import Method, StageMode
from clone.drive.stage import StageFit, fit_to_stage
from clone.model.canvas import full_frame_canvas
from clone.model.reference import LAYOUT, ReferenceModel, file_sha256, load_reference_model
from clone.runtime.generate import generate_frames, side_by_side_frame
from clone.runtime.pipeline import BackgroundSink
from pose_io.atomic import check_new_output
from pose_io.errors import InputError
from pose_io.track import PoseTrack
from retarget.baselines.global_scale import ScaleStats, apply_global_scale, scale_stats

log = logging.getLogger(__name__)



METHODS = tuple(m.value for m in Method)
STAGES = tuple(s.value for s in StageMode)
DEFAULT_MODEL = "ref_model.pt"


@dataclass(frozen=True)
class DriveResult:
    """What a drive wrote."""

    out: Path
    frames: int
    fps: float
    size: tuple[int, int]
    method: str
    poses_out: Path | None
    seconds: float
    stage_share: float = 0.0  # share of frames that were off the reference's stage and moved onto it


def read_driver(path: str | os.PathLike, max_gap: int = 5) -> PoseTrack:
    """The driver's track as body15, gaps of at most ``max_gap`` frames filled linearly."""
    from pose_io.readers import read_track

    return driver_track(read_track(path), max_gap, str(path))


def driver_track(track: PoseTrack, max_gap: int = 5, name: str = "driver") -> PoseTrack:
    """A driver's track as `clone drive` uses it: body15, gaps of at most ``max_gap`` frames filled linearly."""
    from pose_io.clean import fill_gaps

    track = track.to_layout(LAYOUT)
    if not (~track.missing).any():
        raise InputError(f"{name}: no visible joints in any frame")
    if max_gap > 0:
        track, _ = fill_gaps(track, max_gap)
    return track


# ------------------------------------------------------------------------------------------------ methods


def retargeting_weights(model: ReferenceModel, weights: str | os.PathLike | None) -> Path:
    """The weights file to retarget with: ``weights``; else the file the model's codes came from, when it is
    still there unchanged (a model trained with ``--weights X`` keeps using X); else the shipped weights."""
    from retarget.api import PACKAGED_WEIGHTS

    if weights is not None:
        return Path(weights)
    hint = Path(model.codes_weights_path) if model.codes_weights_path else None
    if hint is not None and hint.is_file() and file_sha256(hint) == model.codes_weights:
        log.info("retargeting with %s, the weights the model's codes came from", hint)
        return hint
    if PACKAGED_WEIGHTS.is_file():
        return PACKAGED_WEIGHTS
    if model.reference_codes is None:
        raise InputError("this reference model holds no retargeting codes (it was trained without retargeting "
                         "weights) and none are shipped; pass --weights FILE or use --method global-scale")
    raise InputError(f"the retargeting weights this model's codes came from ({model.codes_weights_path}) are "
                     "gone and none are shipped; pass --weights FILE or use --method global-scale")


def load_driving_retargeter(
    weights: str | os.PathLike | None, device: str = "cpu", refine_steps: int | None = None
):  # -> retarget.api.Retargeter | NumpyRetargeter
    """The retargeting network for driving: ``refine_steps`` motion-code refinement steps (None: inference's
    default); with 0, the numpy backend when the weights have an up-to-date export (nothing to refine there)."""
    from retarget.api import load_retargeter
    from retarget.inference.config import InferenceConfig

    config = None if refine_steps is None else InferenceConfig(refine_steps=refine_steps)
    return load_retargeter(weights, device=device, config=config, backend="auto" if refine_steps == 0 else "torch")


def retarget_onto(
    driver: PoseTrack, model: ReferenceModel, weights: str | os.PathLike | None, device: str = "cpu",
    refine_steps: int | None = None,
) -> PoseTrack:
    """The driver's motion performed by the reference, in the reference's pixels (retargeting network).

    Uses the codes stored in the model when the same weights made them; otherwise computes them from the
    reference track stored in the model. ``refine_steps``: motion-code refinement steps (None: inference's
    default; 0: the encoder's codes as they are, on the numpy backend when the weights have an export).
    """
    from retarget.api import ReferenceCodes

    path = retargeting_weights(model, weights)
    retargeter = load_driving_retargeter(path, device, refine_steps)
    if model.reference_codes is not None and file_sha256(path) == model.codes_weights:
        codes = ReferenceCodes.from_dict(model.reference_codes)
    else:
        log.info("computing the reference's codes from its stored track with %s", path)
        codes = retargeter.reference_codes(model.reference_track)
    return retargeter.retarget(driver, codes)


def global_scale_onto(driver: PoseTrack, model: ReferenceModel) -> PoseTrack:
    """The driver moved and scaled per frame onto the reference's feet positions (Everybody Dance Now)."""
    if model.scale_stats is None:
        raise InputError("the reference never shows its ankles, so --method global-scale is not available; "
                         "use --method retarget or none")
    return global_scale_to(driver, model.scale_stats, model.canvas.image_size)


def global_scale_to(driver: PoseTrack, target: ScaleStats, image_size: tuple[int, int]) -> PoseTrack:
    """The driver moved and scaled per frame onto a reference's scale statistics, in its ``image_size``."""
    layout = driver.joint_layout
    joints = apply_global_scale(driver.joints, layout, scale_stats(driver.joints, layout), target)
    return driver.replace(joints=joints, image_size=image_size)


def drive_poses(
    driver: PoseTrack, model: ReferenceModel, method: Method | str, weights: str | os.PathLike | None = None,
    device: str = "cpu", stage: StageMode | str = StageMode.REFERENCE, foot_lock: bool = True,
    refine_steps: int | None = None,
) -> tuple[PoseTrack, StageFit | None]:
    """The driver's poses in the reference's pixels, and how they were kept on the reference's stage.

    Args:
        driver: the driver's track.
        model: the reference model.
        method: one of :data:`METHODS`.
        weights: retargeting weights (see :func:`retargeting_weights`).
        device: where the retargeting network runs.
        stage: one of :data:`STAGES`: ``reference`` keeps the ``retarget`` and ``global-scale`` results on the
            part of the frame the reference occupied (:func:`clone.drive.stage.fit_to_stage`); ``raw`` does not.
        foot_lock: clean up the ``retarget`` result's foot skating with the driver's foot contacts
            (:func:`pose_io.feet.lock_feet`), before the stage fit, which moves the whole track at once.
        refine_steps: motion-code refinement steps of ``retarget`` (see :func:`retarget_onto`).

    Returns:
        ``(track, fit)``; ``fit`` is None when the stage was not applied (``raw``, or ``--method none``).
    """
    try:
        method, stage = Method(method), StageMode(stage)
    except ValueError:
        if method not in METHODS:
            raise InputError(f"unknown --method {method!r}; valid: {', '.join(METHODS)}") from None
        raise InputError(f"unknown --stage {stage!r}; valid: {', '.join(STAGES)}") from None
    if method is Method.NONE:
        if driver.image_size != model.canvas.image_size:
            log.warning("driver frames are %dx%d, the reference's %dx%d; --method none uses the coordinates "
                        "as they are", *driver.image_size, *model.canvas.image_size)
        return driver.replace(image_size=model.canvas.image_size), None
    if method is Method.RETARGET:
        driven = retarget_onto(driver, model, weights, device, refine_steps)
    else:
        driven = global_scale_onto(driver, model)
    return finish_driven(driven, driver, model.reference_track, method is Method.RETARGET, stage, foot_lock)


def finish_driven(
    driven: PoseTrack, driver: PoseTrack, reference: PoseTrack, retargeted: bool,
    stage: StageMode | str = StageMode.REFERENCE, foot_lock: bool = True,
) -> tuple[PoseTrack, StageFit | None]:  # fmt: skip
    """What follows moving the driver onto the reference: a retargeted track's foot skating cleaned with the
    driver's contacts (``foot_lock``), then the whole track kept on the reference's stage (``stage``).

    Returns:
        ``(track, fit)`` as :func:`drive_poses`.
    """
    if retargeted and foot_lock:
        from pose_io.feet import lock_feet

        driven = lock_feet(driven, driver)
    if StageMode(stage) is StageMode.RAW:
        return driven, None
    return fit_to_stage(driven, reference)


def move_onto_reference(
    driver: PoseTrack, model: ReferenceModel, method: Method | str, weights: str | os.PathLike | None = None,
    device: str = "cpu", stage: StageMode | str = StageMode.REFERENCE, foot_lock: bool = True,
    refine_steps: int | None = None,
) -> PoseTrack:
    """The driver's poses in the reference's pixels (see :func:`drive_poses`, which also says how far they
    were moved to stay on the reference's stage)."""
    return drive_poses(driver, model, method, weights, device, stage, foot_lock, refine_steps)[0]


# ------------------------------------------------------------------------------------------------ command


def check_poses_out(track: PoseTrack, path: Path, overwrite: bool) -> None:
    """Fail before anything is written when ``path`` cannot take the driven track."""
    from pose_io.writers import output_format

    check_new_output(path, overwrite)
    if output_format(path) == "openpose":
        visible = track.joints[~track.missing]
        if len(visible) and (visible < 0).any():
            raise InputError(f"{path}: driven poses leave the reference frame (negative coordinates), which "
                             "OpenPose JSON cannot hold; write them to a .npz file instead")


def drive(
    driver_path: str | os.PathLike,
    out: str | os.PathLike,
    *,
    model_path: str | os.PathLike = DEFAULT_MODEL,
    method: Method | str = Method.RETARGET,
    stage: StageMode | str = StageMode.REFERENCE,
    poses_out: str | os.PathLike | None = None,
    side_by_side: bool = False,
    device: torch.device | str = "cpu",
    weights: str | os.PathLike | None = None,
    overwrite: bool = False,
    max_gap: int = 5,
    progress: Callable[[int, int], None] | None = None,
    runtime: str = "auto",
    foot_lock: bool = True,
    refine_steps: int | None = None,
) -> DriveResult:
    """Make a video of the reference performing the driver's motion.

    Args:
        driver_path: the driver's poses (any format ``pose_io`` reads).
        out: the ``.mp4`` to write (H.264, yuv420p, the driver's fps).
        model_path: the reference model from ``clone train-ref``.
        method: ``retarget``, ``global-scale`` or ``none``.
        stage: ``reference``: keep the driven track on the part of the frame the reference occupied; ``raw``:
            as the method left it (see :func:`drive_poses`).
        poses_out: also write the driven poses here (folder: OpenPose JSON; or ``.npz`` / ``.csv``).
        side_by_side: frames show driver skeleton | driven skeleton | result.
        device: where the networks run.
        weights: retargeting weights (default: those the model's codes came from, else the shipped ones).
        overwrite: replace existing outputs.
        max_gap: fill gaps of at most this many frames in the driver (0: none).
        progress: called with (frames done, total) after every frame.
        runtime: the generator's runtime: ``auto`` (int8 ONNX Runtime on a CPU when the ``fast`` extra is
            installed, else torch), ``torch``, ``onnx`` or ``int8`` (see :func:`clone.runtime.generate.build_drive_generator`).
        foot_lock: clean up foot skating of ``retarget`` with the driver's contacts (see :func:`drive_poses`).
        refine_steps: motion-code refinement steps of ``retarget`` (None: inference's default; 0: none, fastest).

    Returns:
        What was written.
    """
    from clone.runtime.onnx import generator_runtime
    from pose_io.video_out import VideoWriter
    from pose_io.writers import write_track

    t0 = time.perf_counter()
    out = Path(out)
    try:
        method = Method(method).value  # the plain name from here on: it ends in DriveResult
    except ValueError:
        raise InputError(f"unknown --method {method!r}; valid: {', '.join(METHODS)}") from None
    try:
        stage = StageMode(stage).value
    except ValueError:
        raise InputError(f"unknown --stage {stage!r}; valid: {', '.join(STAGES)}") from None
    if max_gap < 0:
        raise InputError(f"--max-gap must be >= 0, got {max_gap}")
    try:
        generator_runtime(runtime, torch.device(device))
    except ValueError as err:
        raise InputError(str(err)) from None
    check_new_output(out, overwrite)
    model = load_reference_model(model_path)
    driver = read_driver(driver_path, max_gap)
    driven, fit = drive_poses(driver, model, method, weights, str(device), stage, foot_lock, refine_steps)
    poses_path = Path(poses_out) if poses_out is not None else None
    if poses_path is not None:
        check_poses_out(driven, poses_path, overwrite)

    driver_canvas = full_frame_canvas(driver.image_size, model.canvas.size)
    total = driven.num_frames

    def encode(item: tuple[int, np.ndarray, np.ndarray]) -> None:
        t, pose_map, frame = item
        if side_by_side:
            frame = side_by_side_frame(driver.joints[t], driver_canvas, pose_map, frame, driver.joint_layout)
        video.write(frame)

    # Three stages overlap: pose maps are drawn in a thread (generate_frames), the generator runs here, and
    # frames go to the encoder from another thread; an error in any of them ends the with blocks, which
    # stop the threads and remove the unfinished video.
    with VideoWriter(out, fps=driven.fps, overwrite=overwrite) as video, \
            BackgroundSink(encode, depth=4, name="encode") as sink, \
            closing(generate_frames(model, driven, device, runtime=runtime)) as frames:
        for t, (pose_map, frame) in enumerate(frames):
            sink.put((t, pose_map, frame))
            if progress is not None:
                progress(t + 1, total)
    if poses_path is not None:
        write_track(driven, poses_path, overwrite=overwrite)
    width = model.canvas.size * (3 if side_by_side else 1)
    return DriveResult(out, total, driven.fps, (width, model.canvas.size), method, poses_path,
                       time.perf_counter() - t0, 0.0 if fit is None else fit.share)
