"""Cameras, facing, projection conventions and the framing rule."""

from __future__ import annotations

import numpy as np
import pytest

from retarget.world import (
    VIEW_YAWS,
    WORLD_JOINTS,
    Camera,
    facing_angle,
    frame_camera,
    make_skeleton,
    project,
    retarget_3d,
)
from retarget.world.skeleton import Motion3D, rest_pose

J = WORLD_JOINTS.index


def rotate_y(points: np.ndarray, degrees: float) -> np.ndarray:
    a = np.radians(degrees)
    r = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
    return points @ r.T


def test_view_bins() -> None:
    assert len(VIEW_YAWS) == 13 and VIEW_YAWS[0] == -90 and VIEW_YAWS[-1] == 90
    assert np.allclose(np.diff(VIEW_YAWS), 15)


def test_facing_angle_follows_rotation() -> None:
    pose = rest_pose(make_skeleton(1.7))[None]
    assert facing_angle(pose) == pytest.approx(0.0, abs=1e-9)
    for deg in (30.0, 90.0, -120.0):
        assert facing_angle(rotate_y(pose, deg)) == pytest.approx(deg, abs=1e-6)


def test_front_and_side_views_put_joints_where_expected() -> None:
    pose = rest_pose(make_skeleton(1.7))
    cam = frame_camera(0.0, size=(512, 512))
    xy, depth = project(pose, cam, facing_angle(pose[None]))
    # Front view: the character's own left is on the image right, the head is up (smaller y).
    assert xy[J("l_shoulder"), 0] > xy[J("r_shoulder"), 0]
    assert xy[J("head"), 1] < xy[J("mid_hip"), 1] < xy[J("l_ankle"), 1]
    # The nose is in front of the face: nearer to the camera.
    assert depth[J("nose")] < depth[J("head")]
    # Yaw +90 looks at the character's left side: it faces image left, its left side is nearer.
    xy, depth = project(pose, frame_camera(90.0), 0.0)
    assert xy[J("nose"), 0] < xy[J("head"), 0]
    assert depth[J("l_shoulder")] < depth[J("r_shoulder")]
    xy, _ = project(pose, frame_camera(-90.0), 0.0)
    assert xy[J("nose"), 0] > xy[J("head"), 0]
    # Looking down from above: the head rises less than from level.
    level, _ = project(pose, frame_camera(0.0, 0.0), 0.0)
    above, depth = project(pose, frame_camera(0.0, 30.0), 0.0)
    assert level[J("head"), 1] < above[J("head"), 1]
    assert depth[J("head")] < depth[J("l_ankle")] + 1e-6


def test_framing_rule() -> None:
    cam = frame_camera(45.0, 5.0, size=(640, 480))
    assert (cam.tx, cam.ty, cam.scale) == (320.0, 0.9 * 480, 0.36 * 480)
    # The origin (ground under a Motion3D's first root) lands on (tx, ty) for any view.
    for yaw in VIEW_YAWS:
        xy, _ = project(np.zeros((1, 3)), frame_camera(yaw, 7.0, (512, 512)), facing_deg=33.0)
        np.testing.assert_allclose(xy[0], [256.0, 460.8], atol=1e-4)
    # Explicit origin: a shifted clip lands at the same place.
    pose = rest_pose(make_skeleton(1.7))
    a, _ = project(pose, cam, 0.0)
    b, _ = project(pose + [3.0, 0.0, -2.0], cam, 0.0, origin=[3.0, 0.0, -2.0])
    np.testing.assert_allclose(a, b, atol=1e-4)


def test_facing_is_relative_so_views_do_not_depend_on_world_heading() -> None:
    pose = rest_pose(make_skeleton(1.6))[None]
    turned = rotate_y(pose, 70.0)
    cam = frame_camera(30.0)
    a, _ = project(pose, cam, facing_angle(pose))
    b, _ = project(turned, cam, facing_angle(turned))
    np.testing.assert_allclose(a, b, atol=1e-3)


@pytest.mark.parametrize(("bone", "parent", "factor"), [("l_ankle", "l_knee", 1.25), ("l_wrist", "l_elbow", 0.8),
                                                          ("l_knee", "l_hip", 1.1)])
def test_bone_length_changes_scale_projected_limbs_exactly(bone: str, parent: str, factor: float) -> None:
    """Side view, limbs vertical (parallel to the image plane): pixels scale exactly with the bone."""
    source = make_skeleton(1.75)
    motion = Motion3D(rest_pose(source)[None].repeat(3, axis=0).astype(np.float32), 30.0)
    lengths = source.as_dict()
    lengths[bone] *= factor
    target = type(source).from_dict(lengths)
    cam = frame_camera(90.0)
    before, _ = project(motion.positions, cam, 0.0)
    after, _ = project(retarget_3d(motion, target).positions, cam, 0.0)
    limb_before = np.linalg.norm(before[:, J(bone)] - before[:, J(parent)], axis=-1)
    limb_after = np.linalg.norm(after[:, J(bone)] - after[:, J(parent)], axis=-1)
    np.testing.assert_allclose(limb_before, cam.scale * source.length(bone), rtol=1e-5)
    np.testing.assert_allclose(limb_after / limb_before, factor, rtol=1e-5)


def test_camera_defaults_are_the_framing_rule() -> None:
    assert Camera() == frame_camera(0.0)
