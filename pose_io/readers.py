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
- ``video``: a video file (``.mp4``, ``.mov``, ``.avi``, ``.mkv``, ``.webm`` ...): MediaPipe's 33 points
  extracted once and cached by the video's content (:mod:`pose_io.video_poses`), with the video's fps and
  frame size.

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

Multi-person formats are followed with :func:`pose_io.people.follow_person`. How a track is made from the
detections (fps and size sources, outliers, the person followed) is :mod:`pose_io.summary`; the size
inference and outlier rules are :mod:`pose_io.frame_bounds`.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

from pose_io.errors import InputError
from pose_io.people import DEFAULT_GATE, Detections
from pose_io.read_arrays import read_csv, read_npy, read_npz
from pose_io.read_common import LAYOUT_BY_JOINTS, parse_size
from pose_io.read_json import load_json, read_openpose, read_results
from pose_io.summary import TrackSummary, summarize_detections
from pose_io.track import PoseTrack
from pose_io.video_poses import VIDEO_SUFFIXES, video_track_path

__all__ = [
    "LAYOUT_BY_JOINTS", "READERS", "TrackSummary", "detect_format", "parse_size", "read_detections", "read_track",
    "read_track_summary", "track_from_detections",
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


def detect_format(path: Path) -> str:
    """Format name for ``path``: folders are OpenPose, files go by suffix (JSON by content)."""
    if path.is_dir():
        return "openpose"
    suffix = path.suffix.lower()
    if suffix in (".npz", ".npy", ".csv"):
        return suffix[1:]
    if suffix in VIDEO_SUFFIXES:
        return "video"
    if suffix == ".json":
        data = load_json(path)
        if isinstance(data, dict) and "people" in data:
            raise InputError(f"{path}: is a single OpenPose frame; pass the folder that holds the frames")
        if isinstance(data, list) and data and isinstance(data[0], dict):
            return "alphapose" if isinstance(data[0].get("image_id"), str) else "coco"
        raise InputError(f"{path}: not a COCO or AlphaPose keypoint results list")
    raise InputError(f"{path}: unknown pose file type {suffix or '(no suffix)'}; expected a folder of OpenPose "
                     "JSON, .json (COCO/AlphaPose results), .npz, .npy, .csv or a video")


READERS: dict[str, Callable[[Path], Detections]] = {
    "openpose": read_openpose,
    "coco": lambda p: read_results(p, alphapose=False),
    "alphapose": lambda p: read_results(p, alphapose=True),
    "npz": read_npz,
    "npy": read_npy,
    "csv": read_csv,
    "video": lambda p: read_npz(video_track_path(p)),
}
