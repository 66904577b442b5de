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

Multi-person formats are followed with :func:`pose_io.people.follow_person`.
"""

from __future__ import annotations

import csv
import io
import json
import logging
import math
import os
import re
import zipfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pose_io.errors import InputError
from pose_io.layouts import LAYOUTS, get_layout
from pose_io.people import DEFAULT_GATE, Detections, follow_person
from pose_io.track import PoseTrack

log = logging.getLogger(__name__)

DEFAULT_FPS = 30.0
#: Name of the file our OpenPose writer puts next to the frames (fps, image size, layout).
SIDECAR_NAME = "clone2d_track.json"
SIDECAR_KIND = "clone2d-openpose-folder"
#: Frame numbers may skip, but a run this much longer than the number of files is a naming mistake.
_MAX_SPAN_FACTOR = 100
_MAX_SPAN_MIN = 100_000
_SIZE_STEP = 16

LAYOUT_BY_JOINTS: dict[int, str] = {len(layout): name for name, layout in LAYOUTS.items()}
_KEYPOINTS_RE = re.compile(r"(\d+)_keypoints\.json$")
_NUMBER_RE = re.compile(r"\d+")


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
    """

    track: PoseTrack
    format: str
    people_counts: np.ndarray
    start: int
    lost: tuple[int, ...]
    fps_source: str
    size_source: str


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
    followed = follow_person(detections, person=person, gate=gate)
    fps_source, size_source = "given", "given"
    if fps is None:
        fps_source = "file" if detections.fps is not None else "default"
        fps = detections.fps if detections.fps is not None else DEFAULT_FPS
    if image_size is None:
        size_source = "file"
        image_size = detections.image_size
    if image_size is None and fallback_size is not None:
        size_source = "fallback"
        image_size = fallback_size
    if image_size is None:
        size_source = "inferred"
        image_size = infer_image_size(detections)
        log.info("%s: no image size stored; using %dx%d from the data", detections.source, *image_size)
    try:
        track = PoseTrack(followed.joints, followed.confidence, fps, image_size, detections.layout)
    except InputError as exc:
        raise InputError(f"{detections.source}: {exc}") from None
    return TrackSummary(track, fmt, detections.counts, followed.start, followed.lost, fps_source, size_source)


def detect_format(path: Path) -> str:
    """Format name for ``path``: folders are OpenPose, files go by suffix (JSON by content)."""
    if path.is_dir():
        return "openpose"
    suffix = path.suffix.lower()
    if suffix in (".npz", ".npy", ".csv"):
        return suffix[1:]
    if suffix == ".json":
        data = _load_json(path)
        if isinstance(data, dict) and "people" in data:
            raise InputError(f"{path}: is a single OpenPose frame; pass the folder that holds the frames")
        if isinstance(data, list) and data and isinstance(data[0], dict):
            return "alphapose" if isinstance(data[0].get("image_id"), str) else "coco"
        raise InputError(f"{path}: not a COCO or AlphaPose keypoint results list")
    raise InputError(f"{path}: unknown pose file type {suffix or '(no suffix)'}; expected a folder of OpenPose "
                     "JSON, .json (COCO/AlphaPose results), .npz, .npy or .csv")


def infer_image_size(detections: Detections) -> tuple[int, int]:
    """(width, height): the smallest multiples of 16 containing every visible coordinate of ``detections``."""
    maxima = np.zeros(2)
    for frame in detections.people:
        if len(frame):
            xy = frame[..., :2][frame[..., 2] > 0]
            if len(xy):
                maxima = np.maximum(maxima, np.nanmax(xy, axis=0))
    w, h = (max(_SIZE_STEP, math.ceil((float(v) + 1) / _SIZE_STEP) * _SIZE_STEP) for v in maxima)
    return w, h


def parse_size(text: str) -> tuple[int, int]:
    """``"640x480"`` -> (640, 480); InputError for anything else."""
    m = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", text)
    if not m or int(m.group(1)) <= 0 or int(m.group(2)) <= 0:
        raise InputError(f"image size {text!r}: expected WIDTHxHEIGHT, e.g. 640x480")
    return int(m.group(1)), int(m.group(2))


# ----------------------------------------------------------------------------------------------- helpers


def _load_json(path: Path) -> object:
    try:
        return json.loads(path.read_bytes().decode("utf-8"), parse_constant=_reject_constant)
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as exc:
        raise InputError(f"{path}: not valid JSON ({_short(exc)})") from None
    except ValueError as exc:  # from _reject_constant
        raise InputError(f"{path}: {exc}") from None


def _reject_constant(name: str) -> float:
    raise ValueError(f"non-finite number {name}")


def _short(exc: Exception) -> str:
    return str(exc).splitlines()[0][:120] if str(exc) else exc.__class__.__name__


def _numbers(values: object, where: str) -> np.ndarray:
    """A JSON list of numbers as float64; InputError naming ``where`` for anything else."""
    if not isinstance(values, list) or not all(
        isinstance(v, (int, float)) and not isinstance(v, bool) for v in values
    ):
        raise InputError(f"{where}: keypoints must be a list of numbers")
    try:
        arr = np.array(values, dtype=np.float64)
    except OverflowError:
        raise InputError(f"{where}: keypoint value out of range") from None
    if not np.isfinite(arr).all():
        raise InputError(f"{where}: non-finite keypoint value")
    return arr


def _layout_for(n_values: int, where: str) -> str:
    if n_values % 3 == 0 and n_values // 3 in LAYOUT_BY_JOINTS:
        return LAYOUT_BY_JOINTS[n_values // 3]
    valid = ", ".join(f"{3 * j} ({name})" for j, name in sorted(LAYOUT_BY_JOINTS.items()))
    raise InputError(f"{where}: {n_values} keypoint values; expected one of {valid}")


def _person(values: np.ndarray, n_joints: int) -> np.ndarray:
    """[J*3] flat keypoints -> [J, 3] float32 with NaN coordinates where confidence is 0."""
    p = values.reshape(n_joints, 3).astype(np.float32)
    p[p[:, 2] <= 0, :2] = np.nan
    p[p[:, 2] <= 0, 2] = 0.0
    return p


def _stack(people: list[np.ndarray], n_joints: int) -> np.ndarray:
    """Keep detections with a visible joint; [P, J, 3]."""
    kept = [p for p in people if (p[:, 2] > 0).any()]
    return np.stack(kept) if kept else np.zeros((0, n_joints, 3), dtype=np.float32)


def _frame_range(numbers: list[int], source: Path, what: str) -> tuple[int, int]:
    """(first, count) of the frame run covering ``numbers``; InputError for an absurd span."""
    first, last = min(numbers), max(numbers)
    span = last - first + 1
    if span > max(_MAX_SPAN_FACTOR * len(numbers), _MAX_SPAN_MIN):
        raise InputError(f"{source}: {what} numbers run from {first} to {last} with only {len(numbers)} frames")
    return first, span


def _frame_number(name: str) -> int | None:
    """The last run of digits in a file name's stem (``"frame_0012.jpg"`` -> 12)."""
    found = _NUMBER_RE.findall(Path(name).stem)
    return int(found[-1]) if found else None


# ----------------------------------------------------------------------------------------------- OpenPose


def _read_sidecar(folder: Path) -> dict | None:
    path = folder / SIDECAR_NAME
    if not path.is_file():
        return None
    data = _load_json(path)
    try:
        assert isinstance(data, dict) and data.get("kind") == SIDECAR_KIND
        fps = float(data["fps"])
        w, h = (int(v) for v in data["image_size"])
        layout = get_layout(str(data["layout"])).name
        assert math.isfinite(fps) and fps > 0 and w > 0 and h > 0
    except (AssertionError, KeyError, TypeError, ValueError):
        raise InputError(f"{path}: malformed clone2d sidecar (needs kind, fps, image_size, layout)") from None
    return {"fps": fps, "image_size": (w, h), "layout": layout}


def _read_openpose(folder: Path) -> Detections:
    if not folder.is_dir():
        raise InputError(f"{folder}: OpenPose input must be a folder of *_keypoints.json files")
    entries = sorted(p for p in folder.iterdir() if not p.name.startswith("."))
    files = [p for p in entries if p.name.endswith("_keypoints.json")]
    if not files:
        found = ", ".join(p.name for p in entries[:5]) + (", ..." if len(entries) > 5 else "")
        raise InputError(f"{folder}: no *_keypoints.json files" + (f" (found: {found})" if entries else " (empty)"))
    by_number: dict[int, Path] = {}
    for f in files:
        m = _KEYPOINTS_RE.search(f.name)
        if m is None:
            raise InputError(f"{f}: no frame number before _keypoints.json")
        n = int(m.group(1))
        if n in by_number:
            raise InputError(f"{folder}: two files for frame {n}: {by_number[n].name}, {f.name}")
        by_number[n] = f
    first, count = _frame_range(list(by_number), folder, "frame")
    sidecar = _read_sidecar(folder)
    layout = sidecar["layout"] if sidecar else None
    raw: list[list[np.ndarray]] = []
    for i in range(count):
        f = by_number.get(first + i)
        raw.append([] if f is None else _openpose_frame(f))
    for people in raw:
        for p in people:
            layout = layout or _layout_for(p.size, f"{folder}")
            break
    if layout is None:
        raise InputError(f"{folder}: no person in any frame")
    n_joints = len(get_layout(layout))
    frames = []
    for i, people in enumerate(raw):
        for p in people:
            if p.size != 3 * n_joints:
                f = by_number[first + i]
                raise InputError(f"{f}: {p.size} keypoint values, other frames have {3 * n_joints} ({layout})")
        frames.append(_stack([_person(p, n_joints) for p in people], n_joints))
    single = sidecar is not None
    if single and max(len(f) for f in frames) > 1:
        log.warning("%s: has a clone2d sidecar but several people per frame; following one person", folder)
        single = False
    return Detections(
        people=tuple(frames), layout=layout, fps=sidecar["fps"] if sidecar else None,
        image_size=sidecar["image_size"] if sidecar else None, single=single, source=str(folder),
    )


def _openpose_frame(path: Path) -> list[np.ndarray]:
    """The flat keypoint arrays of the people in one OpenPose frame file (empty arrays skipped)."""
    data = _load_json(path)
    if not isinstance(data, dict) or not isinstance(data.get("people"), list):
        raise InputError(f"{path}: not an OpenPose keypoints file (no \"people\" list)")
    people = []
    for k, person in enumerate(data["people"]):
        if not isinstance(person, dict):
            raise InputError(f"{path}: person {k} is not an object")
        # OpenPose 1.0 wrote "pose_keypoints"; later versions "pose_keypoints_2d".
        values = person.get("pose_keypoints_2d", person.get("pose_keypoints"))
        if values is None:
            raise InputError(f"{path}: person {k} has no pose_keypoints_2d")
        where = f"{path}: person {k}"
        arr = _numbers(values, where)
        if not arr.size:
            continue
        _layout_for(arr.size, where)
        xyc = arr.reshape(-1, 3)
        if ((xyc[:, 2] < 0) | (xyc[:, 2] > 1)).any():
            raise InputError(f"{where}: confidence outside [0, 1]")
        negative = np.flatnonzero((xyc[:, 2] > 0) & (xyc[:, :2] < 0).any(axis=1))
        if len(negative):
            j = int(negative[0])
            raise InputError(f"{where}: joint {j} has negative coordinates {xyc[j, :2].tolist()}")
        people.append(arr)
    return people


# ----------------------------------------------------------------------------------------------- COCO / AlphaPose


def _read_results(path: Path, alphapose: bool) -> Detections:
    data = _load_json(path)
    kind = "AlphaPose" if alphapose else "COCO keypoint"
    if not isinstance(data, list):
        raise InputError(f"{path}: not a {kind} results list")
    entries: list[tuple[int, np.ndarray, object]] = []
    layout: str | None = None
    for k, entry in enumerate(data):
        where = f"{path}: entry {k}"
        if not isinstance(entry, dict) or "image_id" not in entry or "keypoints" not in entry:
            raise InputError(f"{where}: needs image_id and keypoints")
        if entry.get("category_id", 1) != 1:
            continue
        image_id = entry["image_id"]
        if alphapose:
            frame = _frame_number(image_id) if isinstance(image_id, str) else None
            if frame is None:
                raise InputError(f"{where}: no frame number in image_id {image_id!r}")
        else:
            if not isinstance(image_id, int) or isinstance(image_id, bool) or image_id < 0:
                raise InputError(f"{where}: image_id must be a non-negative integer, got {image_id!r}")
            frame = image_id
        values = _numbers(entry["keypoints"], where)
        this = _layout_for(values.size, where)
        if layout is not None and this != layout:
            raise InputError(f"{where}: {values.size} keypoint values, earlier entries have {3 * len(get_layout(layout))}")
        layout = this
        if (values[2::3] < 0).any():
            raise InputError(f"{where}: negative keypoint confidence")
        values[2::3] = np.clip(values[2::3], 0.0, 1.0)
        entries.append((frame, values, entry.get("idx")))
    if layout is None:
        raise InputError(f"{path}: no person detections")
    n_joints = len(get_layout(layout))
    first, count = _frame_range([e[0] for e in entries], path, "frame")
    per_frame: list[list[tuple[np.ndarray, object]]] = [[] for _ in range(count)]
    for frame, values, idx in entries:
        p = _person(values, n_joints)
        if (p[:, 2] > 0).any():
            per_frame[frame - first].append((p, idx))
    people = tuple(_stack([p for p, _ in f], n_joints) for f in per_frame)
    ids = _identities(per_frame, path) if alphapose else None
    return Detections(people=people, layout=layout, ids=ids, source=str(path))


def _identities(per_frame: list[list[tuple[np.ndarray, object]]], path: Path) -> tuple[np.ndarray, ...] | None:
    """AlphaPose ``idx`` values as per-frame id arrays, or None when they do not identify people."""
    out = []
    for frame in per_frame:
        ids = []
        for _, idx in frame:
            if isinstance(idx, list) and len(idx) == 1:
                idx = idx[0]
            if not isinstance(idx, (int, float)) or isinstance(idx, bool) or not math.isfinite(idx):
                if any(i is not None for f in per_frame for _, i in f):
                    log.info("%s: idx is not a number in every detection; tracking by position", path)
                return None
            ids.append(int(idx))
        if len(set(ids)) != len(ids):
            log.info("%s: idx repeats within a frame; tracking by position", path)
            return None
        out.append(np.array(ids, dtype=np.int64))
    return tuple(out)


# ----------------------------------------------------------------------------------------------- arrays


def _single_person(joints: np.ndarray, conf: np.ndarray) -> tuple[np.ndarray, ...]:
    """[T, J, 2] + [T, J] of one person -> per-frame [P, J, 3] with P = 1 where any joint is visible."""
    conf = np.where(np.isfinite(joints).all(axis=-1), np.nan_to_num(conf), 0.0)
    xyc = np.concatenate([joints, conf[..., None]], axis=-1).astype(np.float32)
    xyc[xyc[..., 2] <= 0] = (np.nan, np.nan, 0.0)
    return tuple(_stack([f], joints.shape[1]) for f in xyc)


def _load_array(path: Path, what: str) -> object:
    try:
        return np.load(path, allow_pickle=False)
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
        raise InputError(f"{path}: cannot read as {what} ({_short(exc)})") from None


def _check_array(arr: object, path: Path, name: str, ndim: int) -> np.ndarray:
    if not isinstance(arr, np.ndarray) or arr.ndim != ndim or not np.issubdtype(arr.dtype, np.number):
        shape = getattr(arr, "shape", None)
        raise InputError(f"{path}: {name} must be a {ndim}-D numeric array, got shape {shape}")
    if np.isinf(arr).any():
        raise InputError(f"{path}: {name} has infinite values")
    return arr.astype(np.float32)


def _layout_from_joints(n_joints: int, path: Path) -> str:
    if n_joints not in LAYOUT_BY_JOINTS:
        valid = ", ".join(f"{j} ({n})" for j, n in sorted(LAYOUT_BY_JOINTS.items()))
        raise InputError(f"{path}: {n_joints} joints; expected one of {valid}")
    return LAYOUT_BY_JOINTS[n_joints]


def _read_npy(path: Path) -> Detections:
    arr = _check_array(_load_array(path, "a .npy array"), path, "the array", 3)
    if arr.shape[2] not in (2, 3) or arr.shape[0] == 0:
        raise InputError(f"{path}: expected an array [T, J, 2] or [T, J, 3], got shape {arr.shape}")
    layout = _layout_from_joints(arr.shape[1], path)
    conf = arr[..., 2] if arr.shape[2] == 3 else np.ones(arr.shape[:2], dtype=np.float32)
    _check_confidence(conf, path)
    return Detections(_single_person(arr[..., :2], conf), layout, single=True, source=str(path))


def _check_confidence(conf: np.ndarray, path: Path) -> None:
    c = np.nan_to_num(conf)
    if (c < 0).any() or (c > 1 + 1e-6).any():
        raise InputError(f"{path}: confidence outside [0, 1]")


def _read_npz(path: Path) -> Detections:
    archive = _load_array(path, "a .npz archive")
    if not isinstance(archive, np.lib.npyio.NpzFile):
        raise InputError(f"{path}: not a .npz archive")
    with archive:
        missing = [k for k in ("joints", "confidence") if k not in archive.files]
        if missing:
            raise InputError(f"{path}: lacks {', '.join(missing)} (keys: {', '.join(archive.files) or 'none'})")
        try:
            joints = _check_array(archive["joints"], path, "joints", 3)
            conf = _check_array(archive["confidence"], path, "confidence", 2)
            fps = float(archive["fps"]) if "fps" in archive.files else None
            size = tuple(int(v) for v in archive["image_size"]) if "image_size" in archive.files else None
            layout = str(archive["layout"]) if "layout" in archive.files else None
        except (ValueError, TypeError, OSError, zipfile.BadZipFile) as exc:
            raise InputError(f"{path}: malformed entry ({_short(exc)})") from None
    if joints.shape[2] != 2 or joints.shape[0] == 0 or conf.shape != joints.shape[:2]:
        raise InputError(f"{path}: joints {joints.shape} / confidence {conf.shape}; expected [T, J, 2] / [T, J]")
    if layout is None:
        layout = _layout_from_joints(joints.shape[1], path)
    elif layout not in LAYOUTS or len(LAYOUTS[layout]) != joints.shape[1]:
        raise InputError(f"{path}: layout {layout!r} does not fit {joints.shape[1]} joints")
    if fps is not None and not (math.isfinite(fps) and fps > 0):
        raise InputError(f"{path}: fps must be positive, got {fps}")
    if size is not None and (len(size) != 2 or min(size) <= 0):
        raise InputError(f"{path}: image_size must be (width, height) > 0, got {size}")
    _check_confidence(conf, path)
    return Detections(_single_person(joints, conf), layout, fps=fps, image_size=size, single=True, source=str(path))


# ----------------------------------------------------------------------------------------------- CSV


def _read_csv(path: Path) -> Detections:
    try:
        text = path.read_bytes().decode("utf-8")
    except UnicodeDecodeError:
        raise InputError(f"{path}: not a UTF-8 text file") from None
    lines = text.splitlines()
    meta: dict[str, str] = {}
    body_start = 0
    for body_start, line in enumerate(lines):
        if not line.startswith("#"):
            break
        key, sep, value = line[1:].partition(":")
        if sep:
            meta[key.strip().lower()] = value.strip()
    else:
        body_start = len(lines)
    rows = [r for r in csv.reader(io.StringIO("\n".join(lines[body_start:]))) if r]
    if len(rows) < 2:
        raise InputError(f"{path}: needs a header line and at least one frame row")
    header = [h.strip() for h in rows[0]]
    if not header or header[0] != "frame":
        raise InputError(f"{path}: the first column must be 'frame'")
    layout = _csv_layout(header[1:], meta.get("layout"), path)
    lay = get_layout(layout)
    col = {name: i for i, name in enumerate(header)}
    frames: dict[int, np.ndarray] = {}
    for r, row in enumerate(rows[1:], start=2):
        if len(row) != len(header):
            raise InputError(f"{path}: row {r} has {len(row)} cells, the header has {len(header)}")
        try:
            number = int(row[0])
            cells = np.array([float(c) if c.strip() else np.nan for c in row], dtype=np.float64)
        except ValueError:
            raise InputError(f"{path}: row {r} has a non-numeric cell") from None
        if number in frames or number < 0:
            raise InputError(f"{path}: row {r}: frame {number} is negative or repeated")
        p = np.zeros((len(lay), 3), dtype=np.float64)
        for j, name in enumerate(lay.joints):
            p[j, 0], p[j, 1] = cells[col[f"{name}_x"]], cells[col[f"{name}_y"]]
            p[j, 2] = cells[col[f"{name}_c"]] if f"{name}_c" in col else 1.0
        if np.isinf(p).any():
            raise InputError(f"{path}: row {r} has an infinite value")
        frames[number] = p
    first, count = _frame_range(list(frames), path, "frame")
    joints = np.full((count, len(lay), 2), np.nan, dtype=np.float32)
    conf = np.zeros((count, len(lay)), dtype=np.float32)
    for number, p in frames.items():
        joints[number - first] = p[:, :2]
        conf[number - first] = p[:, 2]
    _check_confidence(conf, path)
    fps = _meta_float(meta, "fps", path)
    size = parse_size(meta["image_size"]) if "image_size" in meta else None
    return Detections(_single_person(joints, conf), layout, fps=fps, image_size=size, single=True, source=str(path))


def _meta_float(meta: dict[str, str], key: str, path: Path) -> float | None:
    if key not in meta:
        return None
    try:
        value = float(meta[key])
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise InputError(f"{path}: {key} must be a positive number, got {meta[key]!r}")
    return value


def _csv_layout(columns: list[str], declared: str | None, path: Path) -> str:
    """The layout whose joints the ``<joint>_x/_y[/_c]`` columns name."""
    names = []
    for c in columns:
        stem, _, axis = c.rpartition("_")
        if axis not in ("x", "y", "c") or not stem:
            raise InputError(f"{path}: column {c!r} is not <joint>_x, <joint>_y or <joint>_c")
        names.append(stem)
    joints = set(names)
    candidates = [declared] if declared else list(LAYOUTS)
    for name in candidates:
        if name not in LAYOUTS:
            raise InputError(f"{path}: unknown layout {name!r}; valid: {', '.join(sorted(LAYOUTS))}")
        lay = LAYOUTS[name]
        if joints == set(lay.joints) and all(f"{j}_x" in columns and f"{j}_y" in columns for j in lay.joints):
            if len(columns) != len(set(columns)):
                raise InputError(f"{path}: repeated column")
            return name
    raise InputError(f"{path}: columns do not name the joints of {declared or 'any known layout'}")


READERS: dict[str, Callable[[Path], Detections]] = {
    "openpose": _read_openpose,
    "coco": lambda p: _read_results(p, alphapose=False),
    "alphapose": lambda p: _read_results(p, alphapose=True),
    "npz": _read_npz,
    "npy": _read_npy,
    "csv": _read_csv,
}
