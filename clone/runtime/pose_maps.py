"""The pose maps a reference model's generator reads: a track drawn on the reference's canvas, chunk by chunk.

Shared by the drive loop (:mod:`clone.runtime.generate`) and the int8 calibration (:mod:`clone.runtime.int8`).
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

from clone.model.canvas import image_to_canvas, render_pose_map
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


__all__ = ["draw_pose_maps"]
