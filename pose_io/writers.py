"""Writing pose tracks, atomically; every format here reads back identical with :func:`read_track`.

Every writer is linear in the track length: the missing mask and the values are taken from the track
once, then formatted row by row (``bench/io.py`` measures the rates).

Formats (``fmt``, detected from the path unless given):

- ``openpose``: a folder (a path without suffix) of ``<stem>_000000000000_keypoints.json`` files, one
  per frame, ``<stem>`` being the folder's name: ``{"version": 1.3, "people": [{"pose_keypoints_2d":
  [x, y, c, ...]}]}``; a missing joint is ``0, 0, 0`` and a frame with no visible joint has no person.
  Values are written with 9 significant digits, enough for float32 to come back bit for bit. OpenPose
  files hold neither fps nor image size, so a sidecar ``clone2d_track.json`` (``kind``, ``fps``,
  ``image_size``, ``layout``, ``frames``) goes into the folder; our reader honours it, other tools
  ignore it. OpenPose never writes negative coordinates and our reader rejects them, so a track with
  a visible joint left of or above the image cannot be written in this format (use ``.npz``).
- ``npz``: ``joints`` [T, J, 2] float32 (NaN = missing), ``confidence`` [T, J] float32, ``fps``
  float64, ``image_size`` int64 [2] (width, height), ``layout`` str.
- ``csv``: ``# fps: ...``, ``# image_size: WxH``, ``# layout: ...`` lines, a header
  ``frame,<joint>_x,<joint>_y,<joint>_c,...`` and one row per frame; missing joints have empty x/y
  cells and confidence 0.
"""

from __future__ import annotations

import json
import logging
import os
from collections.abc import Callable
from pathlib import Path

import numpy as np

from pose_io.atomic import atomic_dir, atomic_file
from pose_io.errors import InputError
from pose_io.read_json import SIDECAR_KIND, SIDECAR_NAME
from pose_io.track import PoseTrack

log = logging.getLogger(__name__)

#: Rows formatted at once by the text writers.
_CHUNK = 10_000


def write_track(track: PoseTrack, path: str | os.PathLike, fmt: str | None = None, overwrite: bool = False) -> Path:
    """Write ``track`` to ``path`` atomically (nothing appears unless the whole write succeeds).

    Args:
        track: the pose track.
        path: output file (``.npz``, ``.csv``) or folder (OpenPose).
        fmt: one of :data:`WRITERS`; detected from ``path`` when None.
        overwrite: replace an existing ``path``; otherwise an existing path is an InputError.

    Returns:
        ``path``.

    Raises:
        InputError: an unknown format, an existing ``path`` without ``overwrite``, or a track with no visible joint
            in any frame (every reader refuses such a file: "no person in any frame").
    """
    path = Path(path)
    fmt = output_format(path) if fmt is None else fmt
    try:
        writer = WRITERS[fmt]
    except KeyError:
        raise InputError(f"unknown output pose format {fmt!r}; valid: {', '.join(sorted(WRITERS))}") from None
    if track.missing.all():
        raise InputError(f"{path}: nothing to write: no frame of the track shows a joint")
    writer(track, path, overwrite)
    log.info("wrote %s (%d frames, %s)", path, track.num_frames, fmt)
    return path


def output_format(path: Path) -> str:
    """``.npz`` / ``.csv`` by suffix; a path without suffix (or an existing folder) is an OpenPose folder."""
    suffix = path.suffix.lower()
    if suffix in (".npz", ".csv"):
        return suffix[1:]
    if path.is_dir() or not suffix:
        return "openpose"
    raise InputError(f"{path}: cannot write pose files of type {suffix}; use a folder (OpenPose JSON), .npz or .csv")


def _row_format(n_values: int) -> str:
    """A %-format for ``n_values`` comma-separated floats; 9 significant digits bring any float32 back exactly."""
    return ",".join(["%.9g"] * n_values)


def _write_openpose(track: PoseTrack, path: Path, overwrite: bool) -> None:
    visible = ~track.missing
    negative = visible & (track.joints < 0).any(axis=-1)
    if negative.any():
        t, j = (int(v) for v in np.argwhere(negative)[0])
        name = track.joint_layout.joints[j]
        raise InputError(
            f"{path}: OpenPose JSON cannot hold negative coordinates ({name} at frame {t}); write .npz instead"
        )
    xyc = np.concatenate([np.nan_to_num(track.joints), track.confidence[..., None]], axis=-1)  # [T, J, 3]
    row = _row_format(xyc.shape[1] * 3)
    anyone = visible.any(axis=1).tolist()  # [T]
    stem = path.name
    with atomic_dir(path, overwrite=overwrite) as tmp:
        for t in range(track.num_frames):
            if anyone[t]:
                values = row % tuple(xyc[t].ravel().tolist())
                people = f'[{{"pose_keypoints_2d":[{values}]}}]'
            else:
                people = "[]"
            (tmp / f"{stem}_{t:012d}_keypoints.json").write_text(f'{{"version":1.3,"people":{people}}}\n')
        sidecar = {
            "kind": SIDECAR_KIND, "fps": track.fps, "image_size": list(track.image_size),
            "layout": track.layout, "frames": track.num_frames,
        }
        (tmp / SIDECAR_NAME).write_text(json.dumps(sidecar, indent=1) + "\n")


def _write_npz(track: PoseTrack, path: Path, overwrite: bool) -> None:
    # Stored, not deflated: deflating took 4-5x the time of the stored write for little (a retargeted 120-frame
    # body15 track: 23 KB stored, 13 KB deflated; coordinates hardly compress). Every npz reader takes both.
    with atomic_file(path, overwrite=overwrite) as tmp, open(tmp, "wb") as f:
        np.savez(
            f,
            joints=track.joints,
            confidence=track.confidence,
            fps=np.float64(track.fps),
            image_size=np.array(track.image_size, dtype=np.int64),
            layout=np.array(track.layout),
        )


def _write_csv(track: PoseTrack, path: Path, overwrite: bool) -> None:
    joints = track.joint_layout.joints
    header = [
        f"# fps: {track.fps!r}",
        f"# image_size: {track.image_size[0]}x{track.image_size[1]}",
        f"# layout: {track.layout}",
        ",".join(["frame"] + [f"{n}_{a}" for n in joints for a in ("x", "y", "c")]),
    ]
    # One format string per row over the whole array, in chunks (memory stays flat): linear in the track
    # length. A missing joint has NaN x/y (formatted "nan", then emptied) and confidence 0.
    values = np.concatenate([track.joints, track.confidence[..., None]], axis=-1)  # [T, J, 3]
    values = values.reshape(track.num_frames, -1)  # [T, J * 3]
    row = "%d," + _row_format(values.shape[1]) + "\n"
    with atomic_file(path, overwrite=overwrite) as tmp, open(tmp, "w", encoding="utf-8") as f:
        f.write("\n".join(header) + "\n")
        for start in range(0, track.num_frames, _CHUNK):
            chunk = values[start : start + _CHUNK].tolist()  # [N][J * 3] Python floats
            f.write("".join(row % (t, *cells) for t, cells in enumerate(chunk, start)).replace("nan", ""))


WRITERS: dict[str, Callable[[PoseTrack, Path, bool], None]] = {
    "openpose": _write_openpose,
    "npz": _write_npz,
    "csv": _write_csv,
}
