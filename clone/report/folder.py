"""The report folder: may a report be written there, and an atomic stage that becomes it.

A report folder carries a marker file, ``.clone2d-report``; only a folder with the marker may be replaced, and
only when the caller asks for it. The folder is built in a temporary sibling and renamed into place
(``pose_io.atomic.atomic_dir``), so a failed run leaves nothing behind.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from pathlib import Path

from pose_io.atomic import atomic_dir
from pose_io.errors import InputError

MARKER = ".clone2d-report"
_MARKER_TEXT = "made by clone report; `clone report --overwrite` may replace this folder\n"


def check_report_dir(out_dir: Path, overwrite: bool) -> None:
    """Raise InputError unless a report may be written to ``out_dir``.

    A new path is fine; an existing report folder (with the marker) only with ``overwrite``; anything else
    that exists (a file, a folder not made by a report) never.

    Args:
        out_dir: the report folder the user named.
        overwrite: whether the user allowed replacing an existing report.

    Raises:
        InputError: ``out_dir`` may not be written.
    """
    if not out_dir.exists() and not out_dir.is_symlink():
        return
    if not out_dir.is_dir() or out_dir.is_symlink():
        raise InputError(f"{out_dir}: exists and is not a report folder; choose another --out")
    if not (out_dir / MARKER).is_file():
        raise InputError(
            f"{out_dir}: exists and was not made by `clone report` (no {MARKER}); choose another --out"
        )
    if not overwrite:
        raise InputError(f"{out_dir}: report already exists; pass --overwrite to replace it")


@contextlib.contextmanager
def report_dir(out_dir: str | os.PathLike, overwrite: bool = False) -> Iterator[Path]:
    """Yield an empty temporary folder that becomes ``out_dir`` (marker included) when the block succeeds.

    The folder gets the permissions of a plain ``mkdir`` (``atomic_dir`` applies the process umask), so a
    report can be shared like any other output.

    Args:
        out_dir: the report folder.
        overwrite: replace an existing report folder.

    Raises:
        InputError: before anything is written, when ``check_report_dir`` refuses ``out_dir``.
    """
    out_dir = Path(out_dir)
    check_report_dir(out_dir, overwrite)
    with atomic_dir(out_dir, overwrite=True) as stage:
        yield stage
        (stage / MARKER).write_text(_MARKER_TEXT)
