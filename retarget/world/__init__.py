"""The motion world: real motion capture replayed on many synthetic skeletons and seen from many views.

Numpy only (no torch): ``retarget`` training code turns the arrays into tensors itself.

- ``load_motion``: BVH / AMC of known rigs -> ``Motion3D`` on the canonical 18-joint skeleton.
- ``mocap``: the BVH and ASF/AMC readers and forward kinematics ``load_motion`` builds on.
- ``Skeleton``, ``skeleton_of``, ``retarget_3d``: skeletons and 3D retargeting; ``sample_skeleton``, ``NAMED_CHARACTERS``: characters.
- ``Camera``, ``CameraSpread`` (random training cameras), ``frame_camera``, ``facing_angle``, ``project``, ``VIEW_YAWS``: views and the framing rule.
- ``MotionWorld``: the cached dataset of labelled (motion, character, view) windows.
"""

from retarget.world.camera import (
    CANVAS_SIZE,
    MAX_PITCH,
    VIEW_YAWS,
    Camera,
    CameraSpread,
    facing_angle,
    frame_camera,
    ground_origin,
    project,
)
from retarget.world.characters import NAMED_CHARACTERS, make_skeleton, sample_skeleton
from retarget.world.config import default_cache_dir
from retarget.world.dataset import MotionWorld
from retarget.world.rig_names import RIGS
from retarget.world.rigs import load_motion
from retarget.world.skeleton import (
    BONES,
    WORLD_JOINTS,
    Motion3D,
    Skeleton,
    retarget_3d,
    skeleton_of,
)
from retarget.world.split import WindowLabel, WorldSplit

__all__ = [
    "BONES",
    "CANVAS_SIZE",
    "MAX_PITCH",
    "NAMED_CHARACTERS",
    "RIGS",
    "VIEW_YAWS",
    "WORLD_JOINTS",
    "Camera",
    "CameraSpread",
    "Motion3D",
    "MotionWorld",
    "Skeleton",
    "WindowLabel",
    "WorldSplit",
    "default_cache_dir",
    "facing_angle",
    "frame_camera",
    "ground_origin",
    "load_motion",
    "make_skeleton",
    "project",
    "retarget_3d",
    "sample_skeleton",
    "skeleton_of",
]
