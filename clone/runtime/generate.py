"""Frames of a driven track: its pose maps on the reference's canvas, and the reference model's generator run
over them frame after frame, each conditioned on the one it made before (`clone drive`, `clone report`)."""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
import torch
from torch import Tensor

from clone.model.canvas import image_to_canvas, render_pose_map
from clone.model.networks import generator_input
from clone.model.reference import ReferenceModel
from clone.model.tensors import to_images, to_tensor
from clone.runtime.pipeline import prefetch
from clone.runtime.pose_maps import draw_pose_maps
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


def generate_frames(
    model: ReferenceModel, track: PoseTrack, device: torch.device | str = "cpu", chunk: int = 16,
    runtime: str = "auto",
) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """Run the generator over a track in the reference's pixels.

    Pose maps are drawn (in a background thread, :func:`draw_pose_maps`) and moved to the device ``chunk``
    frames at a time; a temporal generator then runs frame after frame on its own previous output (each
    frame yielded as soon as it is made), a non-temporal one on the whole chunk. A generator trained with a
    background plate composites its frames over the plate stored in the model.

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
    size = model.canvas.size
    prev = torch.zeros(1, 3, size, size, device=device)  # no previous frame yet: zeros, as in training
    plate = model.plate_tensor(device)  # [1, 3, S, S], or None for a model trained without one
    # Later chunks are drawn in a thread while the generator works on this one (clone.runtime.pipeline).
    for maps in prefetch(draw_pose_maps(model, track, chunk), depth=2, name="draw-pose-maps"):
        # The grad mode is entered and left between yields: a context held across a yield would leak into
        # the caller, and interleaved streams would restore each other's modes in the wrong order.
        with torch.inference_mode():
            pose = to_tensor(maps).to(device)  # [C, 3, S, S]
        if not model.temporal:
            with torch.inference_mode():
                frames = to_images(net(pose, plate))  # [C, S, S, 3]
            yield from zip(maps, frames)
            continue
        for i in range(len(maps)):  # one frame at a time, so the encoder gets each as soon as it is made
            with torch.inference_mode():
                prev = net(generator_input(pose[i:i + 1], prev), plate)  # [1, 3, S, S]
                frame = to_images(prev)[0]  # [S, S, 3]
            yield maps[i], frame


def side_by_side_frame(driver_joints: np.ndarray, driver_canvas: Any, pose_map: np.ndarray, frame: np.ndarray,
                       layout: Any) -> np.ndarray:
    """[S, 3S, 3]: the driver's skeleton (its whole frame letterboxed) | the driven pose map | the result."""
    size = frame.shape[0]
    driver_map = render_pose_map(image_to_canvas(driver_joints, driver_canvas), size, layout)
    return np.concatenate([driver_map, pose_map, frame], axis=1)


__all__ = ["build_drive_generator", "generate_frames", "side_by_side_frame"]
