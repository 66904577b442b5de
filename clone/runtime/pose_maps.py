"""What a reference model's generator reads besides its previous frame: a track's pose maps drawn on the
reference's canvas and, for a generator that sees them, its exemplars (:mod:`clone.model.exemplar`), chunk by chunk.

Shared by the drive loop (:mod:`clone.runtime.generate`) and the int8 calibration (:mod:`clone.runtime.int8`).
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

from clone.model.canvas import image_to_canvas, render_pose_map
from clone.model.exemplar import BODY, drive_choices
from clone.model.reference import ReferenceModel
from pose_io.track import PoseTrack


def draw_pose_maps(model: ReferenceModel, track: PoseTrack, chunk: int = 16) -> Iterator[np.ndarray]:
    """The pose maps of a track in the reference's pixels, drawn on the reference's canvas.

    Args:
        model: the reference model (its canvas).
        track: poses in the reference's image pixels (body15, or body31 with the details :func:`clone.drive.poses.drive_poses`
            carried over); drawn in the model's pose layout, a body15 model ignoring details.
        chunk: frames per yielded array.

    Yields:
        [C, S, S, 3] uint8 RGB pose maps, ``C = chunk`` except perhaps for the last.
    """
    track = track.to_layout(model.pose_layout)
    for start in range(0, track.num_frames, chunk):
        joints = image_to_canvas(track.joints[start:start + chunk], model.canvas)  # [C, J, 2]
        yield np.stack([render_pose_map(j, model.canvas.size, track.joint_layout) for j in joints])  # [C, S, S, 3]


def draw_exemplars(model: ReferenceModel, track: PoseTrack, chunk: int = 16) -> Iterator[np.ndarray]:
    """The exemplars of a track for a model whose generator sees them: per frame the bank frame chosen for its
    pose (:func:`clone.model.exemplar.drive_choices`) laid onto it; black where fewer than two body joints show.

    Yields:
        [C, S, S, 3] uint8 RGB, chunk by chunk as :func:`draw_pose_maps`.
    """
    bank = model.exemplars
    if bank is None:
        raise ValueError("the model holds no exemplar frames")
    track = track.to_layout(model.pose_layout)
    joints = image_to_canvas(track.joints, model.canvas)  # [T, J, 2]
    shown = np.isfinite(joints[:, :BODY]).all(-1).sum(-1) >= 2  # [T]
    choices = drive_choices(bank, joints) if len(joints) else np.zeros(0, np.int64)
    size = model.canvas.size
    for start in range(0, track.num_frames, chunk):
        stop = min(track.num_frames, start + chunk)
        yield np.stack([bank.exemplar(int(choices[t]), joints[t]) if shown[t]
                        else np.zeros((size, size, 3), np.uint8) for t in range(start, stop)])


def draw_inputs(model: ReferenceModel, track: PoseTrack, chunk: int = 16
                ) -> Iterator[tuple[np.ndarray, np.ndarray | None]]:
    """``(pose maps, exemplars or None)`` of a track, chunk by chunk (:func:`draw_pose_maps`,
    :func:`draw_exemplars`); None for a generator that sees no exemplar."""
    maps = draw_pose_maps(model, track, chunk)
    if not model.sees_exemplar:
        for chunk_maps in maps:
            yield chunk_maps, None
        return
    yield from zip(maps, draw_exemplars(model, track, chunk))


__all__ = ["draw_exemplars", "draw_inputs", "draw_pose_maps"]
