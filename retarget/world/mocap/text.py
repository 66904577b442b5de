"""The text of a mocap file, plain or gzip-compressed."""

from __future__ import annotations

import gzip
from pathlib import Path

from pose_io.errors import InputError


def read_text(path: str | Path) -> str:
    """Text of a plain or gzip-compressed file (gzip is recognised by its magic bytes, not the name).

    Args:
        path: the file.

    Returns:
        The decoded text: UTF-8, or Latin-1 when it is not valid UTF-8 (older exporters).

    Raises:
        InputError: missing or unreadable file, a folder, or broken gzip data.
    """
    path = Path(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise InputError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise InputError(f"{path}: is a folder, not a file") from None
    except OSError as exc:  # permissions, a FIFO, an I/O error
        raise InputError(f"{path}: cannot read ({exc.strerror or exc.__class__.__name__})") from None
    if raw[:2] == b"\x1f\x8b":
        try:
            raw = gzip.decompress(raw)
        except (OSError, EOFError) as exc:
            raise InputError(f"{path}: broken gzip data ({exc})") from None
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        return raw.decode("latin-1")


__all__ = ["read_text"]
