"""The HIERARCHY section of a BVH file: joint names, parents, OFFSETs and channel names.

Joints are numbered in file order (parents before children); an End Site becomes a joint named
``<parent>_End`` with no channels.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

from pose_io.errors import InputError

# A channel name: axis letter then kind, e.g. "Zrotation" or "Xposition" (any case).
CHANNEL_RE = re.compile(r"^([XYZ])(position|rotation)$", re.IGNORECASE)
# Real rigs nest a few dozen joints deep; the parser recurses once per level, so a hostile file nesting
# thousands would hit Python's recursion limit instead of a clear error.
MAX_DEPTH = 256


class _Tokens:
    """Whitespace tokens of a BVH hierarchy with the line of each, for error messages."""

    def __init__(self, text: str, path: str) -> None:
        self.items: list[tuple[str, int]] = []
        for line_no, line in enumerate(text.splitlines(), 1):
            for tok in line.replace("{", " { ").replace("}", " } ").split():
                self.items.append((tok, line_no))
        self.pos = 0
        self.path = path

    def fail(self, what: str) -> InputError:
        line = self.items[min(self.pos, len(self.items) - 1)][1] if self.items else 0
        return InputError(f"{self.path}: broken BVH hierarchy near line {line}: {what}")

    def next(self) -> str:
        if self.pos >= len(self.items):
            raise self.fail("file ends inside the hierarchy")
        tok = self.items[self.pos][0]
        self.pos += 1
        return tok

    def name(self) -> str:
        """The rest of the current line, braces excluded: joint names may hold spaces ("Bip01 L Thigh")."""
        if self.pos >= len(self.items):
            raise self.fail("file ends inside the hierarchy")
        line = self.items[self.pos][1]
        parts = []
        while self.pos < len(self.items):
            tok, tok_line = self.items[self.pos]
            if tok_line != line or tok in "{}":
                break
            parts.append(tok)
            self.pos += 1
        if not parts:
            raise self.fail("joint without a name")
        return " ".join(parts)

    def peek(self) -> str | None:
        return self.items[self.pos][0] if self.pos < len(self.items) else None

    def expect(self, want: str) -> None:
        tok = self.next()
        if tok.upper() != want.upper():
            raise self.fail(f"expected {want!r}, found {tok!r}")

    def number(self) -> float:
        tok = self.next()
        try:
            value = float(tok)
        except ValueError:
            raise self.fail(f"expected a number, found {tok!r}") from None
        if not math.isfinite(value):
            raise self.fail(f"non-finite number {tok!r}")
        return value


@dataclass
class _Joints:
    """The joints read so far, one entry per joint in file order."""

    names: list[str] = field(default_factory=list)
    parents: list[int] = field(default_factory=list)
    offsets: list[list[float]] = field(default_factory=list)
    channels: list[tuple[str, ...]] = field(default_factory=list)


def _channels(toks: _Tokens) -> tuple[str, ...]:
    """The count and names after a ``CHANNELS`` keyword."""
    count = toks.number()
    if count != int(count) or not 0 <= count <= 64:
        raise toks.fail(f"bad channel count {count}")
    chans = tuple(toks.next() for _ in range(int(count)))
    for c in chans:
        if not CHANNEL_RE.match(c):
            raise toks.fail(f"unknown channel {c!r}")
    return chans


def _joint(toks: _Tokens, out: _Joints, parent: int, name: str, end_site: bool, depth: int = 0) -> None:
    """Read one ``{ ... }`` block and, recursively, its children into ``out``."""
    if depth > MAX_DEPTH:
        raise toks.fail(f"joints nested deeper than {MAX_DEPTH} levels")
    me = len(out.names)
    out.names.append(name)
    out.parents.append(parent)
    out.offsets.append([0.0, 0.0, 0.0])
    out.channels.append(())
    toks.expect("{")
    while True:
        tok = toks.next()
        key = tok.upper()
        if key == "}":
            return
        if key == "OFFSET":
            out.offsets[me] = [toks.number() for _ in range(3)]
        elif key == "CHANNELS" and not end_site:
            out.channels[me] = _channels(toks)
        elif key == "JOINT" and not end_site:
            _joint(toks, out, me, toks.name(), False, depth + 1)
        elif key == "END" and not end_site:
            toks.expect("Site")
            _joint(toks, out, me, f"{name}_End", True, depth + 1)
        else:
            raise toks.fail(f"unexpected {tok!r} in joint {name!r}")


def parse_hierarchy(
    text: str, path: str
) -> tuple[list[str], list[int], list[list[float]], list[tuple[str, ...]]]:
    """Parse the text before ``MOTION``.

    Args:
        text: the HIERARCHY section.
        path: file name for messages.

    Returns:
        ``(names, parents, offsets, channels)``, one entry per joint in file order: parent index (-1 for
        a root), OFFSET ``[x, y, z]`` and channel names as written.

    Raises:
        InputError: a malformed hierarchy (naming the line) or repeated joint names.
    """
    toks = _Tokens(text, path)
    toks.expect("HIERARCHY")
    out = _Joints()
    while toks.peek() is not None and toks.peek().upper() == "ROOT":
        toks.next()
        _joint(toks, out, -1, toks.name(), False)
    names = out.names
    if not names:
        raise toks.fail("no ROOT joint")
    if toks.peek() is not None:
        raise toks.fail(f"unexpected {toks.peek()!r} after the hierarchy")
    if len(set(names)) != len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        raise InputError(f"{path}: BVH joint names repeat: {', '.join(dup[:5])}")
    return names, out.parents, out.offsets, out.channels


__all__ = ["CHANNEL_RE", "parse_hierarchy"]
