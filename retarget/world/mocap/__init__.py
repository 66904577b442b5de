"""Motion-capture readers for the motion world: BVH (plain or gzip) and Acclaim ASF/AMC.

Both readers give a ``MocapClip``: ``names``, ``parents``, ``frame_time``, ``num_frames`` and
``global_transforms(joints) -> (rotations [T, N, 3, 3], positions [T, N, 3])`` in the file's own units
and axes. Mapping a rig onto the canonical skeleton, its units and up axis is ``retarget.world.rigs``'s
business.

- ``rotations``: axis and Euler rotation matrices (BVH and Acclaim orders).
- ``kinematics``: ``MocapClip``, the joint tree both readers share, and forward kinematics.
- ``bvh`` (+ ``bvh_hierarchy``): ``read_bvh`` / ``parse_bvh`` -> ``BvhClip``.
- ``asf`` + ``asf_amc``: ``read_asf_amc`` -> ``AcclaimClip``.
- ``text``: a file's text, plain or gzip.
"""

from retarget.world.mocap.asf_amc import AcclaimClip, read_asf_amc
from retarget.world.mocap.bvh import BvhClip, parse_bvh, read_bvh
from retarget.world.mocap.kinematics import MocapClip, forward_kinematics
from retarget.world.mocap.rotations import axis_rotations, euler_matrices
from retarget.world.mocap.text import read_text

__all__ = [
    "AcclaimClip",
    "BvhClip",
    "MocapClip",
    "axis_rotations",
    "euler_matrices",
    "forward_kinematics",
    "parse_bvh",
    "read_asf_amc",
    "read_bvh",
    "read_text",
]
