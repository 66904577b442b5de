"""The character's reference track and its 2D proportions, seen the way the driver's camera sees the driver.

The network takes a reference person's skeleton (and view) code from a pose track of that person. A cartoon
character has none, so one is rendered with the motion world's own tools: the calm opening of the built-in
reference motion (``clone/data``: the dancer stands, sways and moves the arms a little) is replayed on the
character's 3D skeleton (:func:`retarget.world.skeleton.retarget_3d`) and projected
(:func:`retarget.world.camera.project`) at a yaw, standing where the driver stands, with as many pixels per
metre as make a standard 1.75 m body measure as tall as the driver (:func:`pose_io.measures.skeleton_height`).
Without a chosen yaw, the driver's is estimated from how wide its shoulders look against its trunk
(:func:`estimate_yaw`).

The character's 2D proportions are those of its reference track, measured as every limb length in the project
is: the median over frames (:func:`pose_io.measures.reference_limb_lengths`). A moving body's 2D limbs are
shorter than its rest pose's (the head tilts, knees bend, arms swing forward), and the network learned bodies
in motion, so that is the length a retargeted limb can be asked to have.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np

from clone.cartoon.character import STANDARD, CharacterSpec
from clone.demo import demo_motions
from pose_io.measures import reference_limb_lengths, skeleton_height
from pose_io.resample import resample_values
from pose_io.track import PoseTrack
from retarget.inference.placement import Placement, place, placement_of
from retarget.inference.tracks import body15_track, to_body15
from retarget.network.preprocess import LAYOUT
from retarget.world.camera import Camera, facing_angle, ground_origin, project
from retarget.world.skeleton import WORLD_JOINTS, Motion3D, Skeleton, rest_pose, retarget_3d

REFERENCE_FRAMES = 192  # 6.4 s at 30 fps: the built-in reference motion's calm opening
YAW_STEP = 5.0  # degrees between the standard body's renders a yaw estimate interpolates
_BODY15_OF_WORLD = [WORLD_JOINTS.index(name) for name in LAYOUT.joints]


@dataclass(frozen=True)
class Framing:
    """A camera that sees the character as the driver's camera sees the driver.

    Attributes:
        yaw: view yaw in degrees relative to the character's facing (0 = front, +90 = its left side).
        px_per_m: pixels per metre.
        placement: where the driver stands (root x and ground line, in the driver's pixels).
        image_size: (width, height) of the driver's frames.
    """

    yaw: float
    px_per_m: float
    placement: Placement
    image_size: tuple[int, int]

    @property
    def camera(self) -> Camera:
        return Camera(yaw_deg=self.yaw, scale=self.px_per_m, tx=self.placement.root_x, ty=self.placement.ground_y)


def world_to_body15(xy: np.ndarray) -> np.ndarray:
    """[..., 18, 2] projected world joints -> [..., 15, 2] body15 (the same names)."""
    return xy[..., _BODY15_OF_WORLD, :]


def _project(skeleton: Skeleton, camera: Camera, frames: int) -> np.ndarray:
    """[T, 15, 2] float64: the reference motion replayed on ``skeleton``, seen by ``camera``."""
    motion = retarget_3d(_reference_motion(frames), skeleton)
    positions = motion.positions.astype(np.float64)  # [T, 18, 3]
    xy, _ = project(positions, camera, facing_angle(positions), origin=ground_origin(positions))
    return world_to_body15(xy).astype(np.float64)


@cache
def _standard_render(yaw: float) -> np.ndarray:
    """[T, 15, 2] the standard body's reference track at ``yaw``, in metres (x right, y down)."""
    return _project(STANDARD, Camera(yaw_deg=yaw, scale=1.0, tx=0.0, ty=0.0), REFERENCE_FRAMES)


def standard_height_m(yaw: float = 0.0) -> float:
    """Skeleton height of the standard body in its reference track seen at ``yaw``, in metres."""
    return skeleton_height(_standard_render(float(yaw)), LAYOUT)


def _width_ratio(joints: np.ndarray) -> float:
    """Median shoulder-to-shoulder over median neck-to-root distance of [T, 15, 2] joints (NaN allowed)."""
    j = LAYOUT.index
    width = np.linalg.norm(joints[:, j("l_shoulder")] - joints[:, j("r_shoulder")], axis=-1)  # [T]
    trunk = np.linalg.norm(joints[:, j("neck")] - joints[:, j("mid_hip")], axis=-1)  # [T]
    if np.isnan(width).all() or np.isnan(trunk).all():
        return float("nan")
    return float(np.nanmedian(width) / np.nanmedian(trunk))


def estimate_yaw(driver: PoseTrack, name: str = "driver") -> float:
    """The driver's view yaw in degrees (0 = front, +90 = its left side), guessed from its 2D build.

    The shoulders look narrower against the trunk the more the body is turned; the standard body's ratio at
    each yaw gives the angle (so a broad-shouldered driver looks more frontal than it is). The sign comes from
    the nose: a body seen from its left faces image left, its nose left of its neck.
    """
    joints = to_body15(driver, name).joints.astype(np.float64)
    ratio = _width_ratio(joints)
    if not np.isfinite(ratio):
        return 0.0
    yaws = np.arange(0.0, 90.0 + YAW_STEP / 2, YAW_STEP)
    ratios = np.array([_width_ratio(_standard_render(float(y))) for y in yaws])  # falls as the yaw grows
    order = np.argsort(ratios)
    size = float(np.interp(ratio, ratios[order], yaws[order]))
    nose = joints[:, LAYOUT.index("nose"), 0] - joints[:, LAYOUT.index("neck"), 0]  # [T]
    return -size if not np.isnan(nose).all() and np.nanmedian(nose) > 0 else size


def framing_of(driver: PoseTrack, yaw: float = 0.0, name: str = "driver") -> Framing:
    """The framing of ``driver``: its place and scale, seen at ``yaw``.

    Raises:
        InputError: the driver cannot give body15, or its root, ankles or height bones are never seen.
    """
    placement = placement_of(to_body15(driver, name).joints, name)
    return Framing(float(yaw), placement.height / standard_height_m(float(yaw)), placement, driver.image_size)


def rest_joints(spec: CharacterSpec, framing: Framing) -> np.ndarray:
    """[15, 2] float64 body15 joints of the character standing with its arms hanging, as the framing sees it."""
    xy, _ = project(rest_pose(spec.skeleton())[None], framing.camera)  # [1, 18, 2]
    return place(world_to_body15(xy).astype(np.float64), framing.placement)[0]


def reference_track(spec: CharacterSpec, framing: Framing, fps: float, frames: int = REFERENCE_FRAMES) -> PoseTrack:
    """The character performing the built-in reference motion's opening, seen by ``framing``'s camera.

    Args:
        spec: the character.
        framing: camera, scale and place (from :func:`framing_of`).
        fps: frame rate of the track (the driver's: the 30 fps motion is resampled to it).
        frames: frames of the built-in motion used (at its 30 fps).

    Returns:
        body15 track in the driver's pixels, standing where the driver stands.
    """
    motion = _reference_motion(frames)
    joints = _project(spec.skeleton(), framing.camera, frames)  # [T, 15, 2] driver pixels
    joints = place(resample_values(joints, motion.fps, fps), framing.placement)
    return body15_track(joints, fps, framing.image_size)


def character_lengths(reference: PoseTrack) -> tuple[np.ndarray, float]:
    """The character's 2D proportions in pixels, from its reference track.

    Returns:
        ``(lengths, height)``: [L] median length of every body15 limb (``LAYOUT.limbs`` order) and the
        skeleton height.
    """
    return reference_limb_lengths(reference.joints, LAYOUT), skeleton_height(reference.joints, LAYOUT)


@cache
def _reference_motion(frames: int) -> Motion3D:
    motion = demo_motions()["reference"]
    return Motion3D(motion.positions[:frames], motion.fps, motion.name, motion.source)
