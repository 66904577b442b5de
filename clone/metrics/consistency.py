"""Pose consistency of a drive: does the generated person take the pose she was asked for?

MediaPipe Pose (the project's extractor) is run on the generated frames, and the body15 joints it finds are compared
with the driven poses the frames were generated from, both in canvas pixels: PCK@0.1 (the share of joints within a
tenth of the driven body's height) and the median joint error in % of that height. Frames where MediaPipe finds
nobody count every joint as missed, so a smear that no longer looks like a person costs what it should.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from pose_io.compare import pose_error_terms
from pose_io.errors import InputError
from pose_io.layouts import MEDIAPIPE33
from pose_io.measures import skeleton_height
from pose_io.track import PoseTrack


class ConsistencyMeter:
    """Pose consistency measured as frames are made (a context manager around MediaPipe; memory does not grow
    with the frames): ``add(frame, driven)`` per frame, ``scores()`` at the end (see :func:`consistency_scores`).
    """

    def __init__(self) -> None:
        from pose_io.extract import PoseEstimator

        self._estimator = PoseEstimator()
        self._found: list[np.ndarray] = []
        self._driven: list[np.ndarray] = []

    def __enter__(self) -> ConsistencyMeter:  # noqa: PYI034 (typing.Self needs Python 3.11)
        self._estimator.__enter__()
        return self

    def __exit__(self, *exc: object) -> None:
        self._estimator.__exit__(*exc)

    def add(self, frame: np.ndarray, driven: np.ndarray) -> None:
        """One generated frame ([H, W, 3] uint8 RGB) and the [15, 2] body15 pose it was made from, in its pixels."""
        joints, confidence = self._estimator.process(frame)
        found = PoseTrack(joints[None], confidence[None], 30.0, (frame.shape[1], frame.shape[0]), MEDIAPIPE33.name)
        self._found.append(found.to_layout("body15").joints[0])
        self._driven.append(np.asarray(driven, dtype=np.float64))

    def scores(self) -> dict[str, float]:
        """:func:`consistency_scores` of the frames added so far (NaN for none)."""
        if not self._found:
            return {"pck_0.1": float("nan"), "median_error_pct": float("nan"), "found_share": float("nan")}
        return consistency_scores(np.stack(self._found), np.stack(self._driven))


def detected_poses(frames: Iterable[np.ndarray], fps: float = 30.0) -> PoseTrack:
    """MediaPipe's poses of ``frames`` ([H, W, 3] uint8 RGB, one size) as a body15 track (tracking mode)."""
    from pose_io.extract import extract_track

    frames = list(frames)
    if not frames:
        raise ValueError("no frames")
    h, w = frames[0].shape[:2]

    class _Stream:  # what extract_track reads of a Frames
        path, size = "generated frames", (w, h)

        def __init__(self) -> None:
            self.fps = fps

        def __iter__(self):
            return iter(frames)

    return extract_track(_Stream(), on_frame=None).to_layout("body15")  # type: ignore[arg-type]


def pose_consistency(frames: Iterable[np.ndarray], driven: np.ndarray, fps: float = 30.0) -> dict[str, float]:
    """PCK@0.1 and median error (% of height) of MediaPipe on ``frames`` against ``driven``.

    Args:
        frames: the generated frames.
        driven: [T, 15, 2] the body15 poses they were generated from, in the frames' pixels (NaN where missing).
        fps: the frames' rate (MediaPipe's tracking uses it only through the order of frames).

    Returns:
        ``pck_0.1``, ``median_error_pct`` and ``found_share`` (frames where MediaPipe found a person).
    """
    return consistency_scores(detected_poses(frames, fps).joints, driven)


def consistency_scores(found: np.ndarray, driven: np.ndarray) -> dict[str, float]:
    """PCK@0.1 and median error (% of height) of the poses found in generated frames against those asked for.

    Args:
        found: [T, 15, 2] body15 poses MediaPipe found (NaN where it found none).
        driven: [T, 15, 2] the body15 poses the frames were generated from, in the same pixels.

    Returns:
        ``pck_0.1``, ``median_error_pct`` and ``found_share`` (frames where MediaPipe found a person).
    """
    driven = np.asarray(driven, dtype=np.float64)
    try:
        height = skeleton_height(driven, "body15")
    except InputError:  # no legs in the asked poses: the height of their box
        height = float("nan")
    if not np.isfinite(height) or height <= 0:
        visible = driven[np.isfinite(driven).all(axis=-1)]
        height = float(np.ptp(visible[:, 1])) if len(visible) else 1.0
    _, distance = pose_error_terms(found, driven, height)  # [T, 15] in heights, NaN where either is missing
    asked = np.isfinite(driven).all(axis=-1)
    # A joint asked for and not found is a miss, not a joint left out.
    distance = np.where(asked & np.isnan(distance), np.inf, distance)
    scored = distance[asked]
    return {
        "pck_0.1": float(np.mean(scored < 0.1)) if scored.size else float("nan"),
        "median_error_pct": float(np.median(scored) * 100.0) if scored.size else float("nan"),
        "found_share": float(np.isfinite(found).all(axis=-1).any(axis=-1).mean()),
    }
