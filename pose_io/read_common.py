"""Pieces every pose reader shares: reading bytes, frame runs, sizes, keypoint arrays (formats: pose_io.readers)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from pose_io.errors import InputError
from pose_io.layouts import LAYOUTS
from pose_io.limits import MAX_FRAMES, MAX_IMAGE_SIDE, check_image_size

LAYOUT_BY_JOINTS: dict[int, str] = {len(layout): name for name, layout in LAYOUTS.items()}
#: Frame numbers may skip, but a run this much longer than the number of frames given is a naming mistake.
_MAX_SPAN_FACTOR = 100
_MAX_SPAN_MIN = 100_000
#: More digits than this cannot be a frame number or an image side (and Python refuses to parse 4,300+).
_MAX_DIGITS = 18
_SIZE_RE = re.compile(r"\s*(\d+)\s*[xX]\s*(\d+)\s*")


def require_file(path: Path) -> None:
    """InputError naming ``path`` unless it is a regular file (a folder, a FIFO or a broken link is not)."""
    if not path.is_file():
        what = "a folder" if path.is_dir() else "missing" if not path.exists() else "not a regular file"
        raise InputError(f"{path}: cannot read ({what})")


def read_bytes(path: Path) -> bytes:
    """The bytes of a regular file; InputError naming it when it cannot be read (folder, FIFO, permissions)."""
    require_file(path)
    try:
        return path.read_bytes()
    except OSError as exc:
        raise InputError(f"{path}: cannot read ({short_error(exc)})") from None


def short_error(exc: BaseException) -> str:
    """The first line of an exception's message, at most 120 characters."""
    text = str(exc.strerror if isinstance(exc, OSError) and exc.strerror else exc)
    return text.splitlines()[0][:120] if text.strip() else exc.__class__.__name__


def parse_size(text: str, what: str = "image size") -> tuple[int, int]:
    """``"640x480"`` -> (640, 480); InputError for anything else, including sides beyond 16,384 pixels.

    Args:
        text: ``WIDTHxHEIGHT``.
        what: how the message names the value (e.g. ``"<file>: image_size"``).
    """
    m = _SIZE_RE.fullmatch(text)
    if not m:
        raise InputError(f"{what} {text[:40]!r}: expected WIDTHxHEIGHT, e.g. 640x480")
    if max(len(g.lstrip("0")) for g in m.groups()) > _MAX_DIGITS:
        w, h = (g if len(g) <= 8 else g[:8] + "..." for g in m.groups())
        raise InputError(f"{what} {w}x{h}: each side must be a whole number from 1 to {MAX_IMAGE_SIDE} pixels")
    return check_image_size((int(m.group(1)), int(m.group(2))), what)


def frame_range(numbers: list[int], source: Path | str, what: str) -> tuple[int, int]:
    """(first, count) of the frame run covering ``numbers``; InputError for an absurd or too long span."""
    first, last = min(numbers), max(numbers)
    span = last - first + 1
    if span > max(_MAX_SPAN_FACTOR * len(numbers), _MAX_SPAN_MIN) or span > MAX_FRAMES:
        raise InputError(
            f"{source}: {what} numbers run from {first} to {last} with only {len(numbers)} frames"
            + (f" (at most {MAX_FRAMES:,} frames are allowed)" if span > MAX_FRAMES else "")
        )
    return first, span


def frame_number(name: str, where: str) -> int | None:
    """The last run of digits in a file name's stem (``"frame_0012.jpg"`` -> 12), None when there is none."""
    found = re.findall(r"\d+", Path(name).stem)
    if not found:
        return None
    if len(found[-1].lstrip("0")) > _MAX_DIGITS:
        raise InputError(f"{where}: frame number {found[-1][:24]}... is too large")
    return int(found[-1])


def layout_from_joints(n_joints: int, path: Path | str) -> str:
    """The layout with ``n_joints`` joints; InputError listing the valid counts."""
    if n_joints not in LAYOUT_BY_JOINTS:
        valid = ", ".join(f"{j} ({n})" for j, n in sorted(LAYOUT_BY_JOINTS.items()))
        raise InputError(f"{path}: {n_joints} joints; expected one of {valid}")
    return LAYOUT_BY_JOINTS[n_joints]


def check_confidence(conf: np.ndarray, path: Path | str) -> None:
    """InputError when a confidence (NaN counts as 0) lies outside [0, 1]."""
    c = np.nan_to_num(conf)
    if (c < 0).any() or (c > 1 + 1e-6).any():
        raise InputError(f"{path}: confidence outside [0, 1]")


def stack_people(people: list[np.ndarray], n_joints: int) -> np.ndarray:
    """Keep detections with a visible joint; [P, J, 3]."""
    kept = [p for p in people if (p[:, 2] > 0).any()]
    return np.stack(kept) if kept else np.zeros((0, n_joints, 3), dtype=np.float32)


def single_person(joints: np.ndarray, conf: np.ndarray) -> tuple[np.ndarray, ...]:
    """[T, J, 2] + [T, J] of one person -> per-frame [P, J, 3] with P = 1 where any joint is visible."""
    conf = np.where(np.isfinite(joints).all(axis=-1), np.nan_to_num(conf), 0.0)
    xyc = np.concatenate([joints, conf[..., None]], axis=-1).astype(np.float32)  # [T, J, 3]
    xyc[xyc[..., 2] <= 0] = (np.nan, np.nan, 0.0)
    empty = np.zeros((0, joints.shape[1], 3), dtype=np.float32)
    seen = (xyc[..., 2] > 0).any(axis=1)  # [T]
    return tuple(xyc[t : t + 1] if seen[t] else empty for t in range(len(xyc)))
