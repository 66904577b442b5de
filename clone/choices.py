"""Closed sets of names the cloning code accepts, as enums (no torch or OpenCV here: the command line lists them)."""

from __future__ import annotations

from enum import Enum


class Method(str, Enum):
    """How the driver's poses are moved onto the reference (``clone drive --method``)."""

    RETARGET = "retarget"
    GLOBAL_SCALE = "global-scale"
    NONE = "none"


class StageMode(str, Enum):
    """Where a driven track may go (``clone drive --stage``): anywhere in the ``frame`` with its travel kept, on
    the floor the ``reference`` stood on in its video (:mod:`clone.drive.stage`), or its ``raw`` trajectory as the
    method gave it."""

    FRAME = "frame"
    REFERENCE = "reference"
    RAW = "raw"


class CanvasMode(str, Enum):
    """Where the generator's canvas sits: a square ``crop`` around the performer or the ``full`` frame letterboxed."""

    CROP = "crop"
    FULL = "full"


class Align(str, Enum):
    """How a reference's frames and poses are matched: counts must agree (``exact``) or the common prefix (``trim``)."""

    EXACT = "exact"
    TRIM = "trim"


class PrevSource(str, Enum):
    """What the generator is given as the previous frame during training."""

    GENERATED = "generated"  # its own frame for t-1, as when driving (Everybody Dance Now)
    REAL = "real"  # the real previous frame: teacher forcing
