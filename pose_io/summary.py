"""From everybody a pose file holds to one person's track, and how it was made (what ``clone pose info`` shows).

The caller's fps and image size win, then the file's, then a fallback size (the video the poses came from);
otherwise fps is 30 and the size is inferred from the data (:func:`pose_io.frame_bounds.infer_image_size`).
Outlier joints are dropped first (:func:`pose_io.frame_bounds.drop_outliers`, one warning), then one person
is followed (:func:`pose_io.people.follow_person`).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from pose_io.errors import InputError
from pose_io.frame_bounds import drop_outliers, infer_image_size
from pose_io.limits import check_fps, check_image_size
from pose_io.people import DEFAULT_GATE, Detections, follow_person
from pose_io.track import PoseTrack

log = logging.getLogger(__name__)

DEFAULT_FPS = 30.0


@dataclass(frozen=True, eq=False)
class TrackSummary:
    """A track together with how it was read (what ``clone pose info`` shows).

    Attributes:
        track: the followed person's track.
        format: the format read.
        people_counts: [T] int number of people found in each frame.
        start: first frame with anybody in it (where the person was chosen).
        lost: frames with people in which the followed person was not found.
        fps_source: ``"given"``, ``"file"`` or ``"default"``.
        size_source: ``"given"``, ``"file"``, ``"fallback"`` or ``"inferred"``.
        outliers: joints dropped as outliers (see :mod:`pose_io.limits`; a warning is logged too).
    """

    track: PoseTrack
    format: str
    people_counts: np.ndarray
    start: int
    lost: tuple[int, ...]
    fps_source: str
    size_source: str
    outliers: int = 0


def summarize_detections(
    detections: Detections,
    fmt: str,
    person: int | None = None,
    fps: float | None = None,
    image_size: tuple[int, int] | None = None,
    gate: float = DEFAULT_GATE,
    fallback_size: tuple[int, int] | None = None,
) -> TrackSummary:
    """Follow one person through ``detections``; the track plus how it was made (arguments as above)."""
    fps_source, size_source = "given", "given"
    if fps is None:
        fps_source = "file" if detections.fps is not None else "default"
        fps = detections.fps if detections.fps is not None else DEFAULT_FPS
    fps = check_fps(fps, f"{detections.source}: fps" if fps_source == "file" else "fps")
    if image_size is None:
        size_source = "file"
        image_size = detections.image_size
    if image_size is None and fallback_size is not None:
        size_source = "fallback"
        image_size = fallback_size
    if image_size is not None:
        image_size = check_image_size(image_size, f"{detections.source}: image size" if size_source == "file"
                                      else "image size")
    detections, dropped = drop_outliers(detections, image_size)
    if dropped.count:
        log.warning("%s", dropped.message(detections.source))
    if image_size is None:
        size_source = "inferred"
        image_size = infer_image_size(detections)
        log.info("%s: no image size stored; using %dx%d from the data", detections.source, *image_size)
    followed = follow_person(detections, person=person, gate=gate)
    try:
        track = PoseTrack(followed.joints, followed.confidence, fps, image_size, detections.layout)
    except InputError as exc:
        raise InputError(f"{detections.source}: {exc}") from None
    return TrackSummary(track, fmt, detections.counts, followed.start, followed.lost, fps_source, size_source,
                        dropped.count)
