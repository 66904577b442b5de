"""Driving a trained reference model with someone else's poses (`clone drive`): the video.

1. The driver's poses moved onto the reference (:mod:`clone.drive.poses`).
2. Each frame's pose map drawn on the reference's canvas and the generator run frame after frame, each frame
   conditioned on the one it generated before (the first on zeros, as in training).
3. An H.264 mp4 written at the driver's fps, one frame at a time: memory does not grow with the track.

Drawing, the generator and the encoder run side by side in threads (:mod:`clone.runtime.pipeline`).
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from contextlib import closing
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from clone.choices import Method, StageMode
from clone.drive.coverage import Coverage, pose_coverage
from clone.drive.poses import METHODS, STAGES, drive_poses, read_driver
from clone.model.canvas import full_frame_canvas
from clone.model.reference import LAYOUT, load_reference_model
from clone.runtime.generate import generate_frames, side_by_side_frame
from clone.runtime.pipeline import BackgroundSink
from pose_io.atomic import check_new_output
from pose_io.audio import resolve_audio
from pose_io.errors import InputError
from pose_io.track import PoseTrack

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
    stage_share: float = 0.0  # share of frames that were out of bounds (--stage) and moved in
    audio: Path | None = None  # the file whose sound the video carries
    coverage: Coverage | None = None  # how much of the drive the reference's own poses cover


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
    stage: StageMode | str = StageMode.FRAME,
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
    audio: str | os.PathLike | None = "auto",
) -> DriveResult:
    """Make a video of the reference performing the driver's motion.

    Args:
        driver_path: the driver's poses (any format ``pose_io`` reads).
        out: the ``.mp4`` to write (H.264, yuv420p, the driver's fps).
        model_path: the reference model from ``clone train-ref``.
        method: ``retarget``, ``global-scale`` or ``none``.
        stage: ``frame``: keep the driven track inside the model's picture with its travel; ``reference``: on
            the part of the frame the reference occupied; ``raw``: as the method left it (see :func:`drive_poses`).
        poses_out: also write the driven body15 poses here (folder: OpenPose JSON; or ``.npz`` / ``.csv``).
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
        audio: the output's sound: ``auto`` the driver's when it is a video with sound, ``none`` (or None)
            silent, else a file with an audio stream (:func:`pose_io.audio.resolve_audio`).

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
    sound = resolve_audio(audio, driver_path)
    model = load_reference_model(model_path)
    driver = read_driver(driver_path, max_gap, layout=model.pose_layout)
    driven, fit = drive_poses(driver, model, method, weights, str(device), stage, foot_lock, refine_steps)
    poses_path = Path(poses_out) if poses_out is not None else None
    if poses_path is not None:
        check_poses_out(driven.to_layout(LAYOUT), poses_path, overwrite)

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
    with VideoWriter(out, fps=driven.fps, overwrite=overwrite, audio=sound) as video, \
            BackgroundSink(encode, depth=4, name="encode") as sink, \
            closing(generate_frames(model, driven, device, runtime=runtime)) as frames:
        for t, (pose_map, frame) in enumerate(frames):
            sink.put((t, pose_map, frame))
            if progress is not None:
                progress(t + 1, total)
    if poses_path is not None:
        write_track(driven.to_layout(LAYOUT), poses_path, overwrite=overwrite)  # the network's joints
    width = model.canvas.size * (3 if side_by_side else 1)
    return DriveResult(out, total, driven.fps, (width, model.canvas.size), method, poses_path,
                       time.perf_counter() - t0, 0.0 if fit is None else fit.share, sound,
                       pose_coverage(driven, model.reference_track))
