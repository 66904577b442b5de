"""The JSON pose formats (see :mod:`pose_io.readers` for what each holds): folders of OpenPose frames with our
optional sidecar, and COCO / AlphaPose keypoint results; plus the JSON checks they share (finite numbers within
float32 range, a layout from the keypoint count)."""

from __future__ import annotations

import json
import logging
import math
import re
from pathlib import Path

import numpy as np

from pose_io.errors import InputError
from pose_io.layouts import LAYOUTS, get_layout
from pose_io.limits import FLOAT32_MAX, check_fps, check_image_size
from pose_io.people import Detections
from pose_io.read_common import (
    LAYOUT_BY_JOINTS,
    frame_number,
    frame_range,
    read_bytes,
    short_error,
    stack_people,
)

log = logging.getLogger(__name__)

#: Name of the file our OpenPose writer puts next to the frames (fps, image size, layout).
SIDECAR_NAME = "clone2d_track.json"
SIDECAR_KIND = "clone2d-openpose-folder"
_KEYPOINTS_RE = re.compile(r"(\d+)_keypoints\.json$")


def load_json(path: Path) -> object:
    """A JSON file's data; InputError for bytes that are not JSON or numbers that are not finite."""
    raw = read_bytes(path)
    try:
        return json.loads(raw.decode("utf-8"), parse_constant=_reject_constant)
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as exc:
        raise InputError(f"{path}: not valid JSON ({short_error(exc)})") from None
    except ValueError as exc:  # from _reject_constant, or an integer of more than 4,300 digits
        raise InputError(f"{path}: {short_error(exc)}") from None


def _reject_constant(name: str) -> float:
    raise ValueError(f"non-finite number {name}")


def _numbers(values: object, where: str) -> np.ndarray:
    """A JSON list of numbers as float64; InputError naming ``where`` for anything else.

    Values must be finite and within float32 range (tracks store float32; beyond it they would become
    infinite).
    """
    if not isinstance(values, list) or not all(
        isinstance(v, (int, float)) and not isinstance(v, bool) for v in values
    ):
        raise InputError(f"{where}: keypoints must be a list of numbers")
    try:
        arr = np.array(values, dtype=np.float64)
    except OverflowError:
        raise InputError(f"{where}: keypoint value beyond float32 range") from None
    if not np.isfinite(arr).all():
        raise InputError(f"{where}: non-finite keypoint value")
    if arr.size and np.abs(arr).max() > FLOAT32_MAX:
        k = int(np.argmax(np.abs(arr)))
        raise InputError(f"{where}: keypoint value {arr[k]:.3g} (index {k}) is beyond float32 range")
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


# ----------------------------------------------------------------------------------------------- OpenPose


def _read_sidecar(folder: Path) -> dict | None:
    path = folder / SIDECAR_NAME
    if not path.exists():
        return None
    data = load_json(path)
    if not (isinstance(data, dict) and data.get("kind") == SIDECAR_KIND
            and all(k in data for k in ("fps", "image_size", "layout"))):
        raise InputError(f"{path}: malformed clone2d sidecar (needs kind, fps, image_size, layout)")
    layout = data["layout"]
    if not isinstance(layout, str) or layout not in LAYOUTS:
        raise InputError(f"{path}: unknown layout {str(layout)[:40]!r}; valid: {', '.join(sorted(LAYOUTS))}")
    fps = data["fps"]
    if isinstance(fps, bool) or not isinstance(fps, (int, float)):
        raise InputError(f"{path}: fps must be a number, got {str(fps)[:40]!r}")
    return {"fps": check_fps(fps, f"{path}: fps"), "image_size": check_image_size(data["image_size"],
            f"{path}: image_size"), "layout": layout}


def read_openpose(folder: Path) -> Detections:
    """Every person of every frame of an OpenPose folder (frames by number, gaps empty; the sidecar's fps, size
    and layout when there is one)."""
    if not folder.is_dir():
        raise InputError(f"{folder}: OpenPose input must be a folder of *_keypoints.json files")
    try:
        entries = sorted(p for p in folder.iterdir() if not p.name.startswith("."))
    except OSError as exc:
        raise InputError(f"{folder}: cannot list the folder ({short_error(exc)})") from None
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
    first, count = frame_range(list(by_number), folder, "frame")
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
        frames.append(stack_people([_person(p, n_joints) for p in people], n_joints))
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
    data = load_json(path)
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


def read_results(path: Path, alphapose: bool) -> Detections:
    """Every person detection of a COCO keypoint results list (``image_id`` = frame) or AlphaPose's (frame number
    in the file name, ``idx`` identities followed when every detection has one)."""
    data = load_json(path)
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
            frame = frame_number(image_id, where) if isinstance(image_id, str) else None
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
    first, count = frame_range([e[0] for e in entries], path, "frame")
    per_frame: list[list[tuple[np.ndarray, object]]] = [[] for _ in range(count)]
    for frame, values, idx in entries:
        p = _person(values, n_joints)
        if (p[:, 2] > 0).any():
            per_frame[frame - first].append((p, idx))
    people = tuple(stack_people([p for p, _ in f], n_joints) for f in per_frame)
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

__all__ = ["SIDECAR_KIND", "SIDECAR_NAME", "load_json", "read_openpose", "read_results"]
