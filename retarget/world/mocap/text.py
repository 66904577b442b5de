"""The text of a mocap file, plain or gzip-compressed."""

from __future__ import annotations

import gzip
import io
from pathlib import Path

from pose_io.errors import InputError

# Larger than any motion-capture take (the biggest in ../shared is a few MB of text); a cap on what a file, or a
# gzip stream that expands a thousandfold, may make us hold in memory.
MAX_TEXT_BYTES = 256 << 20


def read_text(path: str | Path) -> str:
    """Text of a plain or gzip-compressed file (gzip is recognised by its magic bytes, not the name).

    Args:
        path: the file.

    Returns:
        The decoded text: UTF-8, or Latin-1 when it is not valid UTF-8 (older exporters).

    Raises:
        InputError: missing or unreadable file, a folder, broken gzip data, or more than ``MAX_TEXT_BYTES`` of
            text (read or decompressed).
    """
    path = Path(path)
    too_big = f"{path}: more than {MAX_TEXT_BYTES >> 20} MB of text; not a motion-capture file?"
    try:
        if path.is_file() and path.stat().st_size > MAX_TEXT_BYTES:
            raise InputError(too_big)
        raw = path.read_bytes()
    except FileNotFoundError:
        raise InputError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise InputError(f"{path}: is a folder, not a file") from None
    except OSError as exc:  # permissions, a FIFO, an I/O error
        raise InputError(f"{path}: cannot read ({exc.strerror or exc.__class__.__name__})") from None
    if raw[:2] == b"\x1f\x8b":
        try:
            with gzip.GzipFile(fileobj=io.BytesIO(raw)) as stream:
                raw = stream.read(MAX_TEXT_BYTES + 1)
        except (OSError, EOFError) as exc:
            raise InputError(f"{path}: broken gzip data ({exc})") from None
        if len(raw) > MAX_TEXT_BYTES:
            raise InputError(too_big)
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        return raw.decode("latin-1")


__all__ = ["MAX_TEXT_BYTES", "read_text"]
