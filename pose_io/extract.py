"""Pose extraction from video with MediaPipe's legacy Pose solution (optional dependency).

MediaPipe 0.10.14 pins its own OpenCV, so it is installed without dependencies (see
:data:`INSTALL_HINT`). It is imported only when extraction runs.

What comes out: MediaPipe's 33 landmarks in pixels (normalised x times width, y times height), with
MediaPipe's visibility as confidence. Landmarks that fall outside the frame are guesses, not
detections, and become missing, as do frames where MediaPipe finds nobody.
"""

from __future__ import annotations

import contextlib
import logging
import os
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

import cv2
import numpy as np

from pose_io.atomic import atomic_dir
from pose_io.errors import InputError, raise_if_interrupted
from pose_io.layouts import MEDIAPIPE33
from pose_io.quiet import quiet_native_logs
from pose_io.track import PoseTrack
from pose_io.video import Frames, read_frames
from pose_io.writers import write_track

log = logging.getLogger(__name__)

INSTALL_HINT = (
    "pose extraction needs mediapipe: pip install mediapipe==0.10.14 --no-deps && "
    "pip install absl-py attrs flatbuffers 'protobuf<5'"
)


@dataclass(frozen=True)
class ExtractConfig:
    """Settings of MediaPipe Pose (legacy solution API).

    Attributes:
        model_complexity: 0, 1 or 2; 1 is the model shipped inside the wheel.
        static_image_mode: detect in every frame independently instead of tracking.
        smooth_landmarks: MediaPipe's own temporal filter (only when not static).
        min_detection_confidence: person detector threshold.
        min_tracking_confidence: landmark tracker threshold before re-detecting.
        min_visibility: landmarks with a lower visibility become missing.
    """

    model_complexity: int = 1
    static_image_mode: bool = False
    smooth_landmarks: bool = True
    min_detection_confidence: float = 0.5
    min_tracking_confidence: float = 0.5
    min_visibility: float = 0.0


@dataclass(frozen=True)
class ExtractResult:
    """What :func:`extract_video` wrote.

    Attributes:
        out_dir: the output folder.
        poses_dir: ``out_dir/poses``: OpenPose BODY_25 JSON per frame (with our sidecar).
        frames_dir: ``out_dir/frames``: the video's frames as ``000000.png`` ...
        track: the extracted track in body25.
        frames_with_person: how many frames MediaPipe found a person in.
    """

    out_dir: Path
    poses_dir: Path
    frames_dir: Path
    track: PoseTrack
    frames_with_person: int


def load_mediapipe_pose() -> ModuleType:
    """MediaPipe's legacy pose solution module; InputError with the install line when it is missing."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            from mediapipe.python.solutions import pose
    except ImportError as exc:
        raise_if_interrupted(exc)  # a SIGTERM inside the import is not a missing package
        raise InputError(INSTALL_HINT) from None
    return pose


def landmarks_to_arrays(landmarks: object, size: tuple[int, int], min_visibility: float = 0.0
                        ) -> tuple[np.ndarray, np.ndarray]:
    """MediaPipe normalised landmarks -> ([33, 2] pixel coordinates, [33] confidence).

    Args:
        landmarks: ``results.pose_landmarks`` (a NormalizedLandmarkList) or None.
        size: (width, height) of the frame.
        min_visibility: lower visibilities become missing.
    """
    joints = np.full((len(MEDIAPIPE33), 2), np.nan, dtype=np.float32)
    conf = np.zeros(len(MEDIAPIPE33), dtype=np.float32)
    if landmarks is None:
        return joints, conf
    w, h = size
    for j, lm in enumerate(landmarks.landmark):  # type: ignore[attr-defined]
        x, y, vis = lm.x * w, lm.y * h, float(lm.visibility)
        if 0 <= x < w and 0 <= y < h and vis > min_visibility:
            joints[j] = (x, y)
            conf[j] = min(max(vis, 0.0), 1.0)
    return joints, conf


class PoseEstimator:
    """MediaPipe Pose, one frame at a time (a context manager; its native log lines kept from the user).

    Args:
        config: MediaPipe settings.

    ``estimator.process(frame)`` of an [H, W, 3] uint8 RGB frame gives its ([33, 2] pixels, [33] confidence);
    frames are tracked in the order they are given unless ``config.static_image_mode``.
    """

    def __init__(self, config: ExtractConfig = ExtractConfig()) -> None:
        self.config = config
        self._stack = contextlib.ExitStack()
        self._estimator = None

    def __enter__(self) -> PoseEstimator:  # noqa: PYI034 (typing.Self needs Python 3.11)
        config, stack = self.config, self._stack
        try:
            stack.enter_context(quiet_native_logs())
            stack.enter_context(warnings.catch_warnings())
            mp_pose = load_mediapipe_pose()
            warnings.simplefilter("ignore", UserWarning)  # protobuf deprecation noise from inside mediapipe
            self._estimator = stack.enter_context(mp_pose.Pose(
                static_image_mode=config.static_image_mode,
                model_complexity=config.model_complexity,
                smooth_landmarks=config.smooth_landmarks,
                enable_segmentation=False,
                min_detection_confidence=config.min_detection_confidence,
                min_tracking_confidence=config.min_tracking_confidence,
            ))
        except BaseException:
            stack.close()
            raise
        return self

    def __exit__(self, *exc: object) -> None:
        self._estimator = None
        self._stack.close()

    def process(self, frame: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """([33, 2] pixel coordinates, [33] confidence) of the person MediaPipe finds in ``frame``."""
        if self._estimator is None:
            raise RuntimeError("PoseEstimator.process outside its with block")
        h, w = frame.shape[:2]
        result = self._estimator.process(frame)
        return landmarks_to_arrays(result.pose_landmarks, (w, h), self.config.min_visibility)


def extract_track(
    frames: Frames,
    config: ExtractConfig = ExtractConfig(),
    on_frame: Callable[[int, np.ndarray], None] | None = None,
) -> PoseTrack:
    """Run MediaPipe Pose on every frame.

    Args:
        frames: the frame stream.
        config: MediaPipe settings.
        on_frame: called as ``on_frame(index, frame)`` after each frame (saving, progress).

    Returns:
        A mediapipe33 track with the stream's fps and frame size (frames without a person are all
        missing).
    """
    joints, conf = [], []
    with PoseEstimator(config) as estimator:
        for t, frame in enumerate(frames):
            xy, c = estimator.process(frame)
            joints.append(xy)
            conf.append(c)
            if on_frame is not None:
                on_frame(t, frame)
    if not joints:
        raise InputError(f"{frames.path}: no frames")
    return PoseTrack(np.stack(joints), np.stack(conf), frames.fps, frames.size, MEDIAPIPE33.name)


def extract_video(
    video: str | os.PathLike,
    out_dir: str | os.PathLike,
    overwrite: bool = False,
    config: ExtractConfig = ExtractConfig(),
    progress: Callable[[int, int], None] | None = None,
) -> ExtractResult:
    """Extract poses from a video (or image folder) into ``out_dir/poses`` and ``out_dir/frames``.

    Poses are written as OpenPose BODY_25 JSON (MediaPipe's landmarks mapped by joint name; neck and
    mid-hip are the means of the shoulders and hips; OpenPose's small toes do not exist in MediaPipe
    and are missing). Frames are written as PNG. Nothing appears unless the whole run succeeds.

    Args:
        video: a video file, an image folder or an image.
        out_dir: the output folder (must not exist unless ``overwrite``).
        overwrite: replace an existing ``out_dir``.
        config: MediaPipe settings.
        progress: called as ``progress(done, total)`` after each frame.

    Returns:
        An :class:`ExtractResult`.

    Raises:
        InputError: unreadable video, MediaPipe missing, or no person in any frame.
    """
    with quiet_native_logs():
        load_mediapipe_pose()  # fail before anything is read or written
    frames = read_frames(video)
    total = frames.num_frames if progress is not None else 0
    out_dir = Path(out_dir)
    with atomic_dir(out_dir, overwrite=overwrite) as tmp:
        frames_tmp = tmp / "frames"
        frames_tmp.mkdir()

        def save(t: int, frame: np.ndarray) -> None:
            if not cv2.imwrite(str(frames_tmp / f"{t:06d}.png"), cv2.cvtColor(frame, cv2.COLOR_RGB2BGR)):
                raise OSError(f"{out_dir}: cannot write frame {t}")
            if progress is not None:
                progress(t + 1, total)

        track = extract_track(frames, config, on_frame=save)
        found = int((~track.missing).any(axis=1).sum())
        if found == 0:
            raise InputError(f"{video}: MediaPipe found no person in any of {track.num_frames} frames")
        body = track.to_layout("body25")
        write_track(body, tmp / "poses", fmt="openpose")
    log.info("%s: person found in %d of %d frames", video, found, track.num_frames)
    return ExtractResult(out_dir, out_dir / "poses", out_dir / "frames", body, found)
