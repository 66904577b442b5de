"""The closed sets of values that options of `clone` accept, as enums: typer lists them in ``--help``, completes
them in the shell and rejects any other value before the command runs.

Each option names its enum twice, as the type and as the parser (``Annotated[Method, typer.Option("--method",
parser=Method)]``): typer still lists and completes the values, and a bad one goes through
:meth:`Choice._missing_`, which words it like the library's own errors (typer's reads ``Value error, 'magic' is
not one of 'retarget', ...``), so that the whole line is
``error: Invalid value for '--method': 'magic'; valid: retarget, global-scale, none``.

Every enum is built from the library's own list, kept in light modules (pose_io's readers, writers and joint
layouts; :mod:`clone.choices`; :mod:`retarget.choices`) because typer reads these types whenever it builds the
app, for ``clone --help`` and every shell-completion request, where importing torch would add about 2 s.
"""

from __future__ import annotations

from enum import Enum
from typing import NoReturn

import typer

from clone import choices
from pose_io.layouts import LAYOUTS
from pose_io.readers import READERS
from pose_io.writers import WRITERS
from retarget import choices as retarget_choices


class Choice(str, Enum):
    """Base of the option enums: ``TheEnum(value)`` with a value outside the set is a usage error naming the set."""

    @classmethod
    def _missing_(cls, value: object) -> NoReturn:
        raise typer.BadParameter(f"{value!r}; valid: {', '.join(member.value for member in cls)}")


def _from(library: type[Enum]) -> type[Choice]:
    """The command-line twin of a library enum: same names and values, and one-line errors."""
    return Choice(library.__name__, [(member.name, member.value) for member in library])  # type: ignore[return-value]


Method = _from(choices.Method)
StageMode = _from(choices.StageMode)
CanvasMode = _from(choices.CanvasMode)
Align = _from(choices.Align)
Variant = _from(retarget_choices.Variant)
Ablation = _from(retarget_choices.Ablation)
Split = _from(retarget_choices.Split)

# Built from pose_io's registries, which `clone --help` imports anyway (pose_io is numpy only).
PoseFormat = Choice("PoseFormat", [(name, name) for name in READERS])
OutputFormat = Choice("OutputFormat", [(name, name) for name in WRITERS])
Layout = Choice("Layout", [(name, name) for name in LAYOUTS])
