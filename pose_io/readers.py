"""Reading pose files into :class:`PoseTrack`.

Formats (``fmt``), detected from the path unless given:

- ``openpose``: a folder of per-frame ``*_keypoints.json`` files (``{"people": [{"pose_keypoints_2d":
  [x, y, c, ...]}]}``). Frames are ordered by the number before ``_keypoints.json`` (not by string
  order) and run from the smallest number to the largest; a number missing from that run is a frame
  with nobody in it. The layout comes from the keypoint count (75 values: body25, 54: coco18; any
  layout of ``pose_io.layouts`` by its joint count). A joint with confidence 0 is missing. Negative or
  non-finite values are errors: OpenPose never writes them, so the file is corrupt or foreign. Files
  written by :func:`pose_io.writers.write_track` carry a sidecar ``clone2d_track.json`` (fps, image
  size, layout), which is honoured when present; it makes a written track read back identical.
- ``coco``: a COCO keypoint results JSON: a list of ``{"image_id": int, "category_id": 1,
  "keypoints": [x, y, v] * 17, "score": s}``; ``image_id`` is the frame number.
- ``alphapose``: AlphaPose's results JSON: the same list with ``image_id`` file names (``"12.jpg"``;
  the frame is the last number in the name). When every detection has an ``idx`` (pose tracking on),
  that identity is followed instead of nearest matching. In both result formats confidences are
  clipped to [0, 1] (COCO visibility flags 1/2 and scores above 1 count as 1).
- ``npz``: our own format (keys ``joints`` [T, J, 2], ``confidence`` [T, J], ``fps``, ``image_size``,
  ``layout``), see :mod:`pose_io.writers`.
- ``npy``: an array [T, J, 2] or [T, J, 3] (x, y[, confidence]); the layout comes from J (25 body25,
  15 body15, 18 coco18, 17 coco17, 33 mediapipe33); NaN marks a missing joint.
- ``csv``: optional ``# key: value`` lines (``fps``, ``image_size`` as ``WxH``, ``layout``), then a
  header ``frame,<joint>_x,<joint>_y,<joint>_c,...`` with joint names of one layout (``_c`` columns
  optional, default 1), one row per frame. Empty cells or ``nan`` mark a missing joint; missing frame
  numbers are empty frames.

Frame rate and image size: a value given by the caller wins, then the one stored in the file (npz,
csv header, OpenPose sidecar); otherwise fps is 30 and the image size is inferred from the data: the
smallest multiple of 16 pixels in each direction that contains every coordinate. Pass the real size
(``image_size=`` / ``--size WxH``) when it matters.

Limits (:mod:`pose_io.limits`): values must be finite and within float32 range (beyond it is an error,
never a silently missing joint), arrays must hold real numbers (complex, text or object arrays are
errors), image sides are 1 to 16,384 pixels (a given ``--size``, a stored size and the inferred one
alike), fps 0.01 to 1,000, tracks at most 1,000,000 frames; array headers are checked before any data is
read. A joint far outside the image and far from its body is an outlier: it is dropped as missing before
the person is followed and the size inferred, with ONE warning (``logging.warning``) counting the dropped
joints; ``TrackSummary.outliers`` holds the count.

Multi-person formats are followed with :func:`pose_io.people.follow_person`.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pose_io.errors import InputError
from pose_io.layouts import get_layout
from pose_io.limits import (
    MAX_IMAGE_SIDE,
    Dropped,
    check_fps,
    check_image_size,
    outlier_mask,
)
from pose_io.people import DEFAULT_GATE, Detections, follow_person
from pose_io.read_arrays import read_csv, read_npy, read_npz
from pose_io.read_common import (
    LAYOUT_BY_JOINTS,
    parse_size,
)
from pose_io.read_json import load_json, read_openpose, read_results
from pose_io.track import PoseTrack

log = logging.getLogger(__name__)

DEFAULT_FPS = 30.0
_SIZE_STEP = 16

__all__ = [
    "LAYOUT_BY_JOINTS", "READERS", "TrackSummary", "detect_format",
    "drop_outliers", "infer_image_size", "parse_size", "read_detections", "read_track", "read_track_summary",
    "summarize_detections", "track_from_detections",
]


# ----------------------------------------------------------------------------------------------- entry points


def read_track(
    path: str | os.PathLike,
    fmt: str | None = None,
    person: int | None = None,
    fps: float | None = None,
    image_size: tuple[int, int] | None = None,
    gate: float = DEFAULT_GATE,
) -> PoseTrack:
    """Read one person's pose track from a file or folder.

    Args:
        path: the file or folder (see the module docstring for the formats).
        fmt: format name (one of :data:`READERS`), detected from ``path`` when None.
        person: in multi-person files, the index of the person to follow in the first frame with
            people; None follows the most prominent one.
        fps: frame rate; overrides the file's. Default: the file's, else 30.
        image_size: (width, height); overrides the file's. Default: the file's, else inferred.
        gate: tracking gate, see :func:`pose_io.people.follow_person`.

    Returns:
        The track.

    Raises:
        InputError: missing or malformed input, naming the file and the problem.
    """
    return read_track_summary(path, fmt, person=person, fps=fps, image_size=image_size, gate=gate).track


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


def read_track_summary(
    path: str | os.PathLike,
    fmt: str | None = None,
    person: int | None = None,
    fps: float | None = None,
    image_size: tuple[int, int] | None = None,
    gate: float = DEFAULT_GATE,
    fallback_size: tuple[int, int] | None = None,
) -> TrackSummary:
    """Like :func:`read_track`, also saying how many people each frame had and where fps and size came from.

    Args:
        fallback_size: (width, height) used when neither ``image_size`` nor the file gives one, e.g.
            the size of the video the poses were extracted from (instead of inferring it).
        Others as in :func:`read_track`.
    """
    path = Path(path)
    if not path.exists():
        raise InputError(f"{path}: does not exist")
    fmt = detect_format(path) if fmt is None else fmt
    return summarize_detections(read_detections(path, fmt), fmt, person, fps, image_size, gate, fallback_size)


def read_detections(path: str | os.PathLike, fmt: str | None = None) -> Detections:
    """Read everybody in a pose file or folder, frame by frame (no person chosen yet).

    Args:
        path: the file or folder.
        fmt: format name (one of :data:`READERS`), detected from ``path`` when None.

    Returns:
        The detections, with whatever fps and image size the file stores.
    """
    path = Path(path)
    if not path.exists():
        raise InputError(f"{path}: does not exist")
    fmt = detect_format(path) if fmt is None else fmt
    try:
        reader = READERS[fmt]
    except KeyError:
        raise InputError(f"unknown pose format {fmt!r}; valid: {', '.join(sorted(READERS))}") from None
    return reader(path)


def track_from_detections(
    detections: Detections,
    person: int | None = None,
    fps: float | None = None,
    image_size: tuple[int, int] | None = None,
    gate: float = DEFAULT_GATE,
) -> PoseTrack:
    """Follow one person through ``detections`` and make a track (arguments as in :func:`read_track`)."""
    return summarize_detections(detections, "", person, fps, image_size, gate).track


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


def detect_format(path: Path) -> str:
    """Format name for ``path``: folders are OpenPose, files go by suffix (JSON by content)."""
    if path.is_dir():
        return "openpose"
    suffix = path.suffix.lower()
    if suffix in (".npz", ".npy", ".csv"):
        return suffix[1:]
    if suffix == ".json":
        data = load_json(path)
        if isinstance(data, dict) and "people" in data:
            raise InputError(f"{path}: is a single OpenPose frame; pass the folder that holds the frames")
        if isinstance(data, list) and data and isinstance(data[0], dict):
            return "alphapose" if isinstance(data[0].get("image_id"), str) else "coco"
        raise InputError(f"{path}: not a COCO or AlphaPose keypoint results list")
    raise InputError(f"{path}: unknown pose file type {suffix or '(no suffix)'}; expected a folder of OpenPose "
                     "JSON, .json (COCO/AlphaPose results), .npz, .npy or .csv")


def infer_image_size(detections: Detections) -> tuple[int, int]:
    """(width, height): the smallest multiples of 16 containing every visible coordinate of ``detections``.

    Raises:
        InputError: the joints reach beyond the largest allowed image (16,384 pixels a side).
    """
    maxima = np.zeros(2)
    for frame in detections.people:
        if len(frame):
            xy = frame[..., :2][frame[..., 2] > 0]
            if len(xy):
                maxima = np.maximum(maxima, np.nanmax(xy, axis=0))
    if (maxima + 1 > MAX_IMAGE_SIDE).any():
        raise InputError(
            f"{detections.source}: joints reach ({maxima[0]:.6g}, {maxima[1]:.6g}), beyond the largest allowed "
            f"image ({MAX_IMAGE_SIDE} pixels a side); pass the image size (--size WxH) if the coordinates are pixels"
        )
    w, h = (max(_SIZE_STEP, math.ceil((float(v) + 1) / _SIZE_STEP) * _SIZE_STEP) for v in maxima)
    return w, h


def drop_outliers(detections: Detections, image_size: tuple[int, int] | None) -> tuple[Detections, Dropped]:
    """``detections`` with outlier joints made missing (rules in :mod:`pose_io.limits`), and what was dropped.

    Args:
        detections: everybody in a source.
        image_size: (width, height), or None when it is unknown (to be inferred after this).

    Returns:
        The detections (the same object when nothing was dropped) and a :class:`pose_io.limits.Dropped`.
    """
    counts = detections.counts  # [T]
    if not counts.any():
        return detections, Dropped(0)
    allpeople = np.concatenate([p for p in detections.people if len(p)])  # [N, J, 3]
    xy = np.where((allpeople[..., 2] > 0)[..., None], allpeople[..., :2], np.nan)
    outliers = outlier_mask(xy, image_size)  # [N, J]
    if not outliers.any():
        return detections, Dropped(0)
    n, j = (int(v) for v in np.argwhere(outliers)[0])
    frame_of = np.repeat(np.arange(len(counts)), counts)  # [N]
    names = get_layout(detections.layout).joints
    dropped = Dropped(int(outliers.sum()), int(frame_of[n]), names[j], float(xy[n, j, 0]), float(xy[n, j, 1]))
    allpeople = allpeople.copy()
    allpeople[outliers] = (np.nan, np.nan, 0.0)
    keep = (allpeople[..., 2] > 0).any(axis=1)  # [N] a detection left without any joint goes
    splits = np.cumsum(counts)[:-1]
    people = tuple(p[k] for p, k in zip(np.split(allpeople, splits), np.split(keep, splits)))
    ids = None
    if detections.ids is not None:
        ids = tuple(i[k] for i, k in zip(detections.ids, np.split(keep, splits)))
    return dataclasses.replace(detections, people=people, ids=ids), dropped


READERS: dict[str, Callable[[Path], Detections]] = {
    "openpose": read_openpose,
    "coco": lambda p: read_results(p, alphapose=False),
    "alphapose": lambda p: read_results(p, alphapose=True),
    "npz": read_npz,
    "npy": read_npy,
    "csv": read_csv,
}
