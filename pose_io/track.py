"""The one pose-track type that crosses package borders."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from pose_io.errors import InputError
from pose_io.layouts import JointLayout, convert_arrays, get_layout
from pose_io.limits import (
    MAX_FRAMES,
    MAX_IMAGE_SIDE,
    TRACK_RANGE,
    check_coordinate_range,
    check_fps,
    check_frame_count,
    check_image_size,
    real_array,
)

# No valid coordinate is further from 0 than this: TRACK_RANGE image sizes beyond the largest image.
_MAX_REACH = (TRACK_RANGE + 1) * MAX_IMAGE_SIDE


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
        # In place on our own copies, and reductions rather than [T, J] temporaries: a long track is checked
        # in a few passes (real_array has refused infinities, so NaN is the only value to clean).
        np.copyto(conf, 0.0, where=np.isnan(conf))
        if conf.min() < 0 or conf.max() > 1.0 + 1e-6:  # float32 scalars: compared as the arrays were
            raise InputError("pose track: confidence outside [0, 1]")
        nan = np.isnan(joints)  # [T, J, 2]
        missing = nan[..., 0] | nan[..., 1] | (conf <= 0)  # [T, J]
        if missing.any():
            joints[missing] = np.nan
            conf[missing] = 0.0
        np.clip(conf, 0.0, 1.0, out=conf)
        fps = check_fps(self.fps, "pose track: fps")
        w, h = check_image_size(self.image_size, "pose track: image size")
        check_coordinate_range(joints, (w, h), "pose track", layout.joints)
        self._set(joints, conf, fps, (w, h))

    def _set(self, joints: np.ndarray, confidence: np.ndarray, fps: float, image_size: tuple[int, int]) -> None:
        joints.setflags(write=False)
        confidence.setflags(write=False)
        object.__setattr__(self, "joints", joints)
        object.__setattr__(self, "confidence", confidence)
        object.__setattr__(self, "fps", fps)
        object.__setattr__(self, "image_size", image_size)

    @classmethod
    def complete(
        cls, joints: np.ndarray, fps: float, image_size: tuple[int, int], layout: str, copy: bool = True
    ) -> PoseTrack:
        """A track with every joint present (confidence 1), e.g. synthesised poses.

        The same track, and the same errors in the same order, as ``PoseTrack(joints, ones, fps, image_size,
        layout)``; when the joints are finite and in range, what synthesised ones are, a min and a max settle
        what the constructor checks value by value.

        Args:
            joints: [T, J, 2] pixel coordinates for ``layout``.
            fps: frames per second.
            image_size: (width, height).
            layout: joint layout name.
            copy: False hands a float32 ``joints`` over to the track (made read-only, not copied); the
                caller must not change it afterwards.
        """
        size = len(get_layout(layout))
        if (
            isinstance(joints, np.ndarray) and joints.dtype.kind == "f" and joints.ndim == 3
            and joints.shape[1:] == (size, 2) and 0 < len(joints) <= MAX_FRAMES
        ):  # fmt: skip
            values = joints.astype(np.float32, copy=copy)  # [T, J, 2], ours
            low, high = float(values.min()), float(values.max())  # NaN or infinity fails the bound below
            if max(-low, high) <= _MAX_REACH:  # so real, finite and within float32 range
                fps = check_fps(fps, "pose track: fps")
                w, h = check_image_size(image_size, "pose track: image size")
                reach = TRACK_RANGE * max(w, h)
                if -reach <= low and high <= min(w, h) + reach:  # no joint beyond the coordinate range
                    return cls._from_valid(values, np.ones((len(values), size), np.float32), fps, (w, h), layout)
        return cls(joints, np.ones(np.shape(joints)[:2], dtype=np.float32), fps, image_size, layout)

    @classmethod
    def _from_valid(
        cls, joints: np.ndarray, confidence: np.ndarray, fps: float, image_size: tuple[int, int], layout: str
    ) -> PoseTrack:
        """A track of arrays derived from validated tracks only (a slice, a layout conversion): no checks again.

        Internal: the caller guarantees everything the constructor enforces ([T, J, 2] / [T, J] float32 for
        ``layout``, T >= 1, NaN exactly where confidence is 0, confidence in [0, 1], coordinates in range,
        fps and size already checked) and hands the arrays over (they are made read-only, not copied).
        """
        track = object.__new__(cls)
        object.__setattr__(track, "layout", layout)
        track._set(joints, confidence, fps, image_size)
        return track

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
        joints, conf = self.joints[start:stop], self.confidence[start:stop]
        if not len(joints):
            return self.replace(joints=joints, confidence=conf)  # refused there, with the constructor's message
        # Frames of a valid track are valid: copied (not to pin the whole track) and not checked again.
        return PoseTrack._from_valid(joints.copy(), conf.copy(), self.fps, self.image_size, self.layout)

    def to_layout(self, name: str) -> PoseTrack:
        """This track in another joint layout (joints it cannot give are missing)."""
        source = self.joint_layout
        target = get_layout(name)
        joints, conf = convert_arrays(self.joints, self.confidence, source, target)
        # Copies and means of valid joints, NaN / confidence 0 where a part is missing: valid by construction.
        return PoseTrack._from_valid(joints, conf, self.fps, self.image_size, target.name)

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
