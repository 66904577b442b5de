"""3D references: what a 3D pipeline that knows the true 3D motion and camera would output.

Each takes A's [T, 18, 3] world joints and the two skeletons and returns [T, 18, 3] joints for camera B to
project; they see the 3D truth, which no 2D method has, so they bound what retargeting in 2D can reach.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from retarget.world.skeleton import Skeleton, assemble, bone_vectors, joint_index

Reference3D = Callable[[np.ndarray, Skeleton, Skeleton], np.ndarray]  # (A's joints, A, B) -> joints for B

REFERENCES_3D: dict[str, str] = {
    "3D naive copy": "A's 3D joints unchanged (A's body, not B's), projected by camera B: the error of not "
    "retargeting at all, with the view solved exactly",
    "3D global scale": "A's 3D joints scaled uniformly by height(B) / height(A) about the ground under the first "
    "root, projected by camera B: right view and height, A's proportions (EDN's global scaling with 3D truth)",
    "3D rotation copy": "the paper's 3D baseline with 3D truth: A's joint rotations (bone directions) on B's "
    "bone lengths, A's root path copied unscaled, projected by camera B; its pose is the truth's, so only the "
    "root path (stride length, feet off or through the ground) differs",
}


def naive_copy_3d(pos_a: np.ndarray, skel_a: Skeleton, skel_b: Skeleton) -> np.ndarray:
    """[T, 18, 3] A's joints unchanged (see :data:`REFERENCES_3D`)."""
    return pos_a.copy()


def global_scale_3d(pos_a: np.ndarray, skel_a: Skeleton, skel_b: Skeleton) -> np.ndarray:
    """[T, 18, 3] A's joints scaled by the height ratio about the world origin (ground under the first root)."""
    return pos_a * np.float32(skel_b.height / skel_a.height)


def rotation_copy_3d(pos_a: np.ndarray, skel_a: Skeleton, skel_b: Skeleton) -> np.ndarray:
    """[T, 18, 3] A's bone directions with B's bone lengths on A's root path."""
    vectors = bone_vectors(pos_a.astype(np.float64)) * (skel_b.array / skel_a.array)[:, None]  # [T, 17, 3]
    root = pos_a[:, joint_index("mid_hip")].astype(np.float64)  # [T, 3]
    return assemble(root, vectors).astype(np.float32)


# Row name -> function, in the order of :data:`REFERENCES_3D`.
REFERENCE_FUNCTIONS: dict[str, Reference3D] = {
    "3D naive copy": naive_copy_3d,
    "3D global scale": global_scale_3d,
    "3D rotation copy": rotation_copy_3d,
}
