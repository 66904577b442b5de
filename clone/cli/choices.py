"""The closed sets of values that options of `clone` accept, as enums: typer lists them in ``--help``, completes
them in the shell and rejects any other value before the command runs.

Each option names its enum twice, as the type and as the parser (``Annotated[Method, typer.Option("--method",
parser=Method)]``): typer still lists and completes the values, and a bad one goes through
:meth:`Choice._missing_`, which words it like the library's own errors (typer's reads ``Value error, 'magic' is
not one of 'retarget', ...``), so that the whole line is
``error: Invalid value for '--method': 'magic'; valid: retarget, global-scale, none``.

Where the library keeps its list in a light module (pose_io's readers, writers and joint layouts), the enum is
built from that list. Where the library's enum lives in a module that imports torch or OpenCV
(:class:`clone.drive.Method`, :class:`retarget.model.Variant`, :class:`retarget.losses.Ablation`,
:class:`clone.canvas.CanvasMode`, ``clone.train_ref.data.ALIGN_MODES``), it is written out again here: typer reads
these types whenever it builds the app, for ``clone --help`` and for every shell-completion request too, and
importing torch there would add about 2 s to each (see bench/startup.py). tests/clone/cli/test_choices.py checks
that every copy equals the library's enum.
"""

from __future__ import annotations

from enum import Enum
from typing import NoReturn

import typer

from pose_io.layouts import LAYOUTS
from pose_io.readers import READERS
from pose_io.writers import WRITERS


class Choice(str, Enum):
    """Base of the option enums: ``TheEnum(value)`` with a value outside the set is a usage error naming the set."""

    @classmethod
    def _missing_(cls, value: object) -> NoReturn:
        raise typer.BadParameter(f"{value!r}; valid: {', '.join(member.value for member in cls)}")


class Method(Choice):
    """``clone drive --method``: a copy of :class:`clone.drive.Method`."""

    RETARGET = "retarget"
    GLOBAL_SCALE = "global-scale"
    NONE = "none"


class Variant(Choice):
    """``clone retarget train --variant``: a copy of :class:`retarget.model.Variant`."""

    FULL = "full"
    SKELETON = "skeleton"
    VIEW = "view"


class Ablation(Choice):
    """``clone retarget train --ablation``: a copy of :class:`retarget.losses.Ablation`."""

    FULL = "full"
    NO_TRIPLET = "no-triplet"
    RECON_TRIPLET = "recon-triplet"


class CanvasMode(Choice):
    """``clone train-ref --canvas``: a copy of :class:`clone.canvas.CanvasMode`."""

    CROP = "crop"
    FULL = "full"


class Align(Choice):
    """``clone train-ref --align``: a copy of ``clone.train_ref.data.ALIGN_MODES``."""

    EXACT = "exact"
    TRIM = "trim"


class Split(Choice):
    """``clone retarget eval --split``: the held-out splits of the motion world (``retarget.world.SPLITS``)."""

    TEST = "test"
    VAL = "val"


# Built from pose_io's registries, which `clone --help` imports anyway (pose_io is numpy only).
PoseFormat = Choice("PoseFormat", [(name, name) for name in READERS])
OutputFormat = Choice("OutputFormat", [(name, name) for name in WRITERS])
Layout = Choice("Layout", [(name, name) for name in LAYOUTS])
