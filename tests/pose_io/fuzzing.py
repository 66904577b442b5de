"""Shared pieces of the fuzz tests: example counts, hostile values, and text mutations.

Every fuzz target runs twice: a few dozen examples in the default suite, and ``slow_examples()`` (2,500
by default, ``CLONE2D_FUZZ_EXAMPLES`` to change it) in a ``slow``-marked twin, so that

    pytest -m slow -k fuzz tests/pose_io tests/retarget/world/mocap

generates well over 10,000 cases (npz, CSV, OpenPose/COCO JSON, BVH, and the ``clone pose`` command line).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import Any

import pytest
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st

#: Examples of each fuzz target in the slow run.
SLOW_EXAMPLES_DEFAULT = 2_500


def slow_examples() -> int:
    """Examples per target in the slow run: ``CLONE2D_FUZZ_EXAMPLES`` or 2,500."""
    return int(os.environ.get("CLONE2D_FUZZ_EXAMPLES", SLOW_EXAMPLES_DEFAULT))


def fuzz_settings(max_examples: int) -> settings:
    return settings(max_examples=max_examples, deadline=None, database=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow,
                                           HealthCheck.data_too_large])


def fast_and_slow(make: Callable[[], Callable[..., Any]], fast: int) -> tuple[Callable[..., Any], Callable[..., Any]]:
    """The same hypothesis test with ``fast`` examples, and a ``slow``-marked twin with :func:`slow_examples`.

    Args:
        make: builds the ``@given`` test afresh (settings attach to the object, so each twin needs its own).
        fast: examples in the default suite.
    """
    quick = fuzz_settings(fast)(make())
    long = pytest.mark.slow(fuzz_settings(slow_examples())(make()))
    return quick, long


#: Numbers a hostile file may hold where a coordinate, confidence, fps or size belongs.
HOSTILE_NUMBERS = [
    "0", "-0", "1", "-1", "0.5", "1.5", "-5", "1e6", "-1e6", "1e30", "1e38", "3.5e38", "1e39", "1e308", "-1e308",
    "1e400", "nan", "NaN", "inf", "-inf", "Infinity", "1e-320", "99999999999999999999999", "9" * 400, "16384",
    "16385", "100000", "1000", "1001", "0.001", "1e9", "",
]
HOSTILE_TOKENS = HOSTILE_NUMBERS + ["abc", "0x10", "1_000", " ", "\x00", "é", '"', "'", "{", "}", "[", "]", ",",
                                    "\n", "#", ":", "1,2", "x"]


@st.composite
def mutated_text(draw: st.DrawFn, base: str, tokens: list[str] = HOSTILE_TOKENS, max_edits: int = 4,
                 sep: str | None = None) -> str:
    """``base`` with a few edits: a token replaced or inserted, a line dropped or repeated, the text cut.

    Tokens are split at ``sep`` (default: spaces when the text has any, else commas).
    """
    text = base
    for _ in range(draw(st.integers(0, max_edits))):
        kind = draw(st.sampled_from(["replace", "insert", "drop_line", "dup_line", "cut", "noise"]))
        if not text:
            break
        if kind in ("replace", "insert"):
            split = sep or (" " if " " in text else ",")
            pieces = text.split(split)
            i = draw(st.integers(0, len(pieces) - 1))
            tok = draw(st.sampled_from(tokens) | st.text(max_size=6))
            if kind == "replace":
                pieces[i] = tok
            else:
                pieces.insert(i, tok)
            text = split.join(pieces)
        elif kind in ("drop_line", "dup_line"):
            lines = text.split("\n")
            i = draw(st.integers(0, len(lines) - 1))
            lines[i:i + 1] = [] if kind == "drop_line" else [lines[i], lines[i]]
            text = "\n".join(lines)
        elif kind == "cut":
            text = text[: draw(st.integers(0, len(text)))]
        else:
            i = draw(st.integers(0, len(text)))
            text = text[:i] + draw(st.text(max_size=8)) + text[i:]
    return text
