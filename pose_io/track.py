"""The one pose-track type that crosses package borders."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from pose_io.errors import InputError
from pose_io.layouts import JointLayout, convert_arrays, get_layout
from pose_io.limits import check_coordinate_range, check_fps, check_frame_count, check_image_size, real_array


@dataclass(frozen=True, eq=False)
class PoseTrack:
    """A 2D pose track of one person.

    A joint is missing exactly when its coordinates are NaN; its confidence is then 0. The constructor
    enforces this both ways (a confidence of 0 makes the joint NaN), checks shapes against the layout and
    makes the arrays read-only, so a track can be shared without copies. It also enforces the limits of
    :mod:`pose_io.limits`: real, finite coordinates within float32 range and at most 16 image sizes
    outside the image, image sides up to 16,384 px, 0.01 to 1,000 fps, at most 1,000,000 frames.

    Attributes:
        joints: [T, J, 2] float32 pixel coordinates (x right, y down), NaN where missing.
        confidence: [T, J] float32 in [0, 1].
        fps: frames per second (0.01 to 1,000).
        image_size: (width, height) in pixels of the frame the coordinates refer to.
        layout: name of the joint layout (see ``pose_io.layouts.LAYOUTS``).
    """

    joints: np.ndarray
    confidence: np.ndarray
    fps: float
    image_size: tuple[int, int]
    layout: str

    def __post_init__(self) -> None:
        layout = get_layout(self.layout)
        # Real numbers within float32 range before the cast: complex would lose its imaginary part and
        # 1e39 would become inf silently (limits in pose_io.limits).
        joints = np.array(real_array(self.joints, "pose track: joints"), dtype=np.float32, copy=True)
        if joints.ndim != 3 or joints.shape[2] != 2:
            raise InputError(f"pose track: joints must be [T, J, 2], got shape {tuple(joints.shape)}")
        t, j, _ = joints.shape
        if t == 0:
            raise InputError("pose track: no frames")
        check_frame_count(t, "pose track")
        if j != len(layout):
            raise InputError(f"pose track: layout {layout.name} has {len(layout)} joints, data has {j}")
        conf = np.array(real_array(self.confidence, "pose track: confidence"), dtype=np.float32, copy=True)
        if conf.shape != (t, j):
            raise InputError(f"pose track: confidence must be [{t}, {j}], got {tuple(conf.shape)}")
        conf = np.nan_to_num(conf, nan=0.0)
        if (conf < 0).any() or (conf > 1.0 + 1e-6).any():
            raise InputError("pose track: confidence outside [0, 1]")
        missing = np.isnan(joints).any(axis=-1) | (conf <= 0)
        joints[missing] = np.nan
        conf[missing] = 0.0
        conf = np.clip(conf, 0.0, 1.0)
        fps = check_fps(self.fps, "pose track: fps")
        w, h = check_image_size(self.image_size, "pose track: image size")
        check_coordinate_range(joints, (w, h), "pose track", layout.joints)
        joints.setflags(write=False)
        conf.setflags(write=False)
        object.__setattr__(self, "joints", joints)
        object.__setattr__(self, "confidence", conf)
        object.__setattr__(self, "fps", fps)
        object.__setattr__(self, "image_size", (w, h))

    @property
    def joint_layout(self) -> JointLayout:
        return get_layout(self.layout)

    @property
    def num_frames(self) -> int:
        return int(self.joints.shape[0])

    def __len__(self) -> int:
        return self.num_frames

    @property
    def missing(self) -> np.ndarray:
        """[T, J] bool, True where a joint is missing."""
        return np.isnan(self.joints[..., 0])

    def joint(self, name: str) -> np.ndarray:
        """[T, 2] coordinates of joint ``name``."""
        return self.joints[:, self.joint_layout.index(name)]

    def replace(self, **changes: object) -> PoseTrack:
        """A copy with some fields changed (validated again)."""
        return dataclasses.replace(self, **changes)

    def frames(self, start: int, stop: int) -> PoseTrack:
        """Frames ``start:stop`` as a new track."""
        return self.replace(joints=self.joints[start:stop], confidence=self.confidence[start:stop])

    def to_layout(self, name: str) -> PoseTrack:
        """This track in another joint layout (joints it cannot give are missing)."""
        source = self.joint_layout
        target = get_layout(name)
        joints, conf = convert_arrays(self.joints, self.confidence, source, target)
        return PoseTrack(joints, conf, self.fps, self.image_size, target.name)

    def equals(self, other: PoseTrack, atol: float = 0.0) -> bool:
        """Same layout, fps, size, missing pattern, and coordinates/confidences within ``atol``."""
        return (
            self.layout == other.layout
            and self.image_size == other.image_size
            and abs(self.fps - other.fps) <= 1e-6
            and self.joints.shape == other.joints.shape
            and bool(np.array_equal(self.missing, other.missing))
            and bool(np.allclose(self.joints, other.joints, atol=atol, equal_nan=True))
            and bool(np.allclose(self.confidence, other.confidence, atol=atol))
        )
