"""The demo's output folder: only a folder an earlier demo made is replaced, and only once the new run worked.

The folder carries a marker file; an earlier demo's folder is moved aside while the new one is made, deleted
when the new run succeeds and put back when it fails.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

from pose_io.errors import InputError

MARKER = ".clone2d-demo"


def check_out(out: Path) -> None:
    """Raise InputError unless ``out`` is new or a folder an earlier demo made, in a writable place."""
    from pose_io.outputs import check_writable_folder

    if out.exists() and not (out / MARKER).is_file():
        raise InputError(f"{out}: exists and was not made by `clone demo`; choose another --out")
    check_writable_folder(out.parent, f"--out {out}")


def prepare_out(out: Path) -> Path | None:
    """Make ``out`` ready; an earlier demo's folder is moved aside (returned) and only deleted once the new run
    has finished (:func:`finish_out`), or put back when it fails."""
    check_out(out)
    old = None
    if out.exists():
        old = out.with_name(f".{out.name}.old-{os.getpid()}")
        os.replace(out, old)
    out.mkdir(parents=True)
    (out / MARKER).write_text("made by clone demo; `clone demo` replaces this folder\n")
    return old


def finish_out(out: Path, old: Path | None, ok: bool) -> None:
    """Drop the earlier demo (``ok``) or the half-made new one, whose place the earlier demo takes again."""
    if ok:
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
        return
    shutil.rmtree(out, ignore_errors=True)
    if old is not None:
        os.replace(old, out)
