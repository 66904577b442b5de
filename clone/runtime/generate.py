"""Frames of a driven track: its pose maps on the reference's canvas, and the reference model's generator run
over them frame after frame, each conditioned on the one it made before (`clone drive`, `clone report`)."""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import closing
from typing import Any

import numpy as np
import torch
from torch import Tensor

from clone.model.canvas import image_to_canvas, render_pose_map
from clone.model.face import FACE_CROP, FacePass
from clone.model.networks import generator_input
from clone.model.reference import ReferenceModel
from clone.model.tensors import to_images, to_tensor
from clone.runtime.pipeline import prefetch
from clone.runtime.pose_maps import draw_inputs
from pose_io.errors import InputError
from pose_io.track import PoseTrack

log = logging.getLogger(__name__)


def build_drive_generator(model: ReferenceModel, device: torch.device, runtime: str = "auto") -> Callable[..., Tensor]:
    """The model's generator, ready to drive: the torch module, or its ONNX Runtime export in fp32 or int8.

    Args:
        model: the reference model.
        device: where the generator runs.
        runtime: ``auto`` (int8 ONNX Runtime on a CPU when the ``fast`` extra is installed, else torch),
            ``torch``, ``onnx`` or ``int8`` (see :func:`clone.runtime.onnx.generator_runtime`); ``int8`` falls
            back to ``onnx`` with a warning when quantising fails (:mod:`clone.runtime.int8`).

    Returns:
        ``net(x, plate) -> frame`` on [B, C_in, S, S] / [1, 3, S, S] tensors on ``device``.
    """
    from clone.runtime.onnx import OnnxGenerator, generator_runtime

    try:
        runtime = generator_runtime(runtime, device)
    except ValueError as err:
        raise InputError(str(err)) from None
    if runtime == "int8":
        from clone.runtime.int8 import build_int8_generator

        log.info("running the generator on ONNX Runtime in int8")
        return build_int8_generator(model)
    net = model.build_generator(device)
    if runtime == "torch":
        return net
    log.info("running the generator on ONNX Runtime")
    return OnnxGenerator(net, model.canvas.size, model.generator_config.uses_plate)


def build_drive_face_pass(model: ReferenceModel, device: torch.device, runtime: str = "auto") -> FacePass | None:
    """The model's face pass ready to drive (None without one): on ONNX Runtime (fp32, a few ms a frame) when
    the generator runs there, else torch."""
    from clone.runtime.onnx import OnnxGenerator, generator_runtime

    face_pass = model.build_face_pass(device)
    if face_pass is None or generator_runtime(runtime, device) == "torch":
        return face_pass
    return FacePass(OnnxGenerator(face_pass.net, FACE_CROP, with_plate=False, threads=1), face_pass.radius)


def generate_frames(
    model: ReferenceModel, track: PoseTrack, device: torch.device | str = "cpu", chunk: int = 16,
    runtime: str = "auto",
) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """Run the generator over a track in the reference's pixels.

    Pose maps are drawn (in a background thread, :func:`draw_pose_maps`) and moved to the device ``chunk``
    frames at a time; a temporal generator then runs frame after frame on its own previous output (each
    frame yielded as soon as it is made, or with a face pass once the next one is under way), a non-temporal
    one on the whole chunk. A generator trained with a background plate composites its frames over the plate
    stored in the model; a model with a face pass (:mod:`clone.model.face`) has each frame's face refined
    before it is yielded.

    Args:
        model: the reference model.
        track: body15 poses in the reference's image pixels.
        device: where the generator runs.
        chunk: frames per batch of pose maps.
        runtime: ``auto``, ``torch``, ``onnx`` or ``int8`` (see :func:`build_drive_generator`).

    Yields:
        ``(pose map, frame)`` per track frame, both [S, S, 3] uint8 RGB.
    """
    device = torch.device(device)
    net = build_drive_generator(model, device, runtime)
    face_pass = build_drive_face_pass(model, device, runtime)
    # closed with this generator, so that its drawing thread stops when the caller stops early
    with closing(_generator_frames(model, net, track, device, chunk)) as frames:
        if face_pass is None:
            for pose_map, _pose, frame in frames:
                with torch.inference_mode():
                    image = to_images(frame)[0]  # [S, S, 3]
                yield pose_map, image
            return
        # The face pass of frame t runs in a thread while the generator makes frame t + 1 (it needs the
        # generator's own frame t, not the refined one): on 2 cores it then costs little of the drive's speed.
        centres = torch.from_numpy(_face_centres(model, track)).to(device)  # [T, 2] canvas pixels
        with ThreadPoolExecutor(1, thread_name_prefix="face-pass") as pool:
            pending = None
            for t, (pose_map, pose, frame) in enumerate(frames):
                job = pool.submit(_refined, face_pass, pose_map, pose, frame, centres[t:t + 1])
                if pending is not None:
                    yield pending.result()
                pending = job
            if pending is not None:
                yield pending.result()


def _generator_frames(
    model: ReferenceModel, net: Callable[..., Tensor], track: PoseTrack, device: torch.device, chunk: int,
) -> Iterator[tuple[np.ndarray, Tensor, Tensor]]:
    """The generator's frames of a track, one at a time: ``(pose map [S, S, 3] uint8, pose [1, 3, S, S],
    frame [1, 3, S, S])`` (see :func:`generate_frames`)."""
    size = model.canvas.size
    prev = torch.zeros(1, 3, size, size, device=device)  # no previous frame yet: zeros, as in training
    plate = model.plate_tensor(device)  # [1, 3, S, S], or None for a model trained without one
    # Later chunks are drawn in a thread while the generator works on this one (clone.runtime.pipeline).
    for maps, exemplars in prefetch(draw_inputs(model, track, chunk), depth=2, name="draw-pose-maps"):
        # The grad mode is entered and left between yields: a context held across a yield would leak into
        # the caller, and interleaved streams would restore each other's modes in the wrong order.
        with torch.inference_mode():
            pose = to_tensor(maps).to(device)  # [C, 3, S, S]
            seen = None if exemplars is None else to_tensor(exemplars).to(device)  # [C, 3, S, S]
        if not model.temporal:
            with torch.inference_mode():
                out = net(generator_input(pose, None, seen), plate)  # [C, 3, S, S]
            for i in range(len(maps)):
                yield maps[i], pose[i:i + 1], out[i:i + 1]
            continue
        for i in range(len(maps)):  # one frame at a time, so the encoder gets each as soon as it is made
            with torch.inference_mode():
                # the next frame is conditioned on the generator's own frame, as in training
                ex = None if seen is None else seen[i:i + 1]
                prev = net(generator_input(pose[i:i + 1], prev, ex), plate)  # [1, 3, S, S]
            yield maps[i], pose[i:i + 1], prev


def _refined(face_pass: FacePass, pose_map: np.ndarray, pose: Tensor, frame: Tensor, centre: Tensor
             ) -> tuple[np.ndarray, np.ndarray]:
    """``(pose map, frame [S, S, 3] uint8)`` with the face pass applied (in the face pass's thread)."""
    with torch.inference_mode():
        return pose_map, to_images(face_pass(frame, pose, centre))[0]


def _face_centres(model: ReferenceModel, track: PoseTrack) -> np.ndarray:
    """[T, 2] the face's centre on the canvas in each frame of a driven track (NaN where no face point shows)."""
    from clone.model.face import face_centres

    drawn = track.to_layout(model.pose_layout)
    return face_centres(image_to_canvas(drawn.joints, model.canvas), drawn.joint_layout)


def side_by_side_frame(driver_joints: np.ndarray, driver_canvas: Any, pose_map: np.ndarray, frame: np.ndarray,
                       layout: Any) -> np.ndarray:
    """[S, 3S, 3]: the driver's skeleton (its whole frame letterboxed) | the driven pose map | the result."""
    size = frame.shape[0]
    driver_map = render_pose_map(image_to_canvas(driver_joints, driver_canvas), size, layout)
    return np.concatenate([driver_map, pose_map, frame], axis=1)


__all__ = ["build_drive_face_pass", "build_drive_generator", "generate_frames", "side_by_side_frame"]
