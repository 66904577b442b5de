"""Checks a command runs on every output path BEFORE any work starts, and on the numbers a user's options scale.

Writing happens at the end of a run (atomically, see ``pose_io.atomic``); these checks make a run that would fail
there fail at its start instead, with one clear line, and before anything the user had is touched.
"""

from __future__ import annotations

import math
import os
import tempfile
from collections.abc import Iterable
from pathlib import Path

from pose_io.atomic import nearest_existing
from pose_io.errors import InputError

FOLDER = ""  # the "suffix" of a folder output in ``suffixes``


def check_writable_folder(folder: Path, what: str) -> None:
    """Raise InputError unless new files can be created in ``folder`` (or in the folders it would be made in)."""
    base = nearest_existing(folder)
    if not base.is_dir():
        raise InputError(f"{what}: {base} is not a folder")
    # os.access says yes to root on a read-only mount, so a probe file settles it (and is removed at once).
    if not os.access(base, os.W_OK | os.X_OK):
        raise InputError(f"{what}: cannot write in {base} (permission denied)")
    try:
        fd, probe = tempfile.mkstemp(prefix=".clone2d-probe-", dir=base)
    except OSError as exc:
        raise InputError(f"{what}: cannot write in {base} ({exc.strerror or exc})") from None
    os.close(fd)
    os.unlink(probe)


def check_output(
    path: Path,
    option: str,
    *,
    suffixes: Iterable[str] | None = None,
    overwrite: bool = False,
    replaceable: bool = False,
) -> Path:
    """Check an output path before any work: the right kind, not there already, and its folder writable.

    Args:
        path: where the command will write.
        option: the option or argument that named it (``--out``), for the message.
        suffixes: accepted suffixes, lower case with the dot (``.mp4``); :data:`FOLDER` (``""``) accepts a
            folder (a path without suffix, or an existing folder). None: any file name.
        overwrite: an existing output may be replaced.
        replaceable: the output exists and the command will replace it by itself (``--resume``).

    Returns:
        ``path``.

    Raises:
        InputError: a wrong suffix, an existing folder where a file goes (or a file where a folder goes), an
            existing output without ``overwrite``, or a location that cannot be written.
    """
    path = Path(path)
    allowed = None if suffixes is None else tuple(suffixes)
    wants_folder = allowed is not None and FOLDER in allowed
    file_suffixes = tuple(s for s in allowed or () if s)
    suffix = path.suffix.lower()
    if path.is_dir() and not wants_folder:
        raise InputError(f"{option} {path}: is a folder; give a file name"
                         + (f" ending in {' or '.join(file_suffixes)}" if file_suffixes else ""))
    is_folder_output = wants_folder and (path.is_dir() or (not suffix and not path.is_file()))
    if allowed is not None and not is_folder_output and suffix not in file_suffixes:
        kinds = [*(file_suffixes), *(["a folder"] if wants_folder else [])]
        raise InputError(f"{option} {path}: unsupported type {suffix or '(no suffix)'}; use {' or '.join(kinds)}")
    if wants_folder and path.is_file() and not file_suffixes:
        raise InputError(f"{option} {path}: is a file; give a folder")
    if path.exists() and not (overwrite or replaceable):
        raise InputError(f"{option} {path}: already exists; choose another path or pass --overwrite")
    check_writable_folder(path.parent, f"{option} {path}")
    return path


def check_number(option: str, value: float | None, low: float | None = None, high: float | None = None,
                 *, low_open: bool = False) -> None:
    """Raise InputError unless ``value`` (when given) is finite and in [low, high] (``(low, high]`` if ``low_open``)."""
    if value is None:
        return
    if not math.isfinite(value):
        raise InputError(f"{option}: must be a finite number, got {value}")
    too_low = low is not None and (value <= low if low_open else value < low)
    if too_low or (high is not None and value > high):
        lo = "" if low is None else f"{'>' if low_open else '>='} {low:g}"
        hi = "" if high is None else f"<= {high:g}"
        raise InputError(f"{option}: must be {' and '.join(p for p in (lo, hi) if p)}, got {value:g}")


