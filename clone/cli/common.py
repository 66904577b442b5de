"""Shared pieces of the command line: one-line errors, the console, device option parsing."""

from __future__ import annotations

import functools
import logging
import math
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated, Any, TypeVar

import typer
from rich.console import Console
from typer.core import TyperGroup

from pose_io.errors import InputError

try:  # typer >= 0.26 vendors click and does not re-export its usage errors (fastapi/typer discussion 1832)
    from typer._click.exceptions import NoArgsIsHelpError, UsageError
except ImportError:  # older typer runs on click itself
    from click.exceptions import NoArgsIsHelpError, UsageError  # type: ignore[no-redef]

F = TypeVar("F", bound=Callable[..., object])

console = Console(stderr=True)


def user_errors(func: F) -> F:
    """Turn InputError (and missing files) into one ``error: ...`` line on stderr and exit code 2."""

    @functools.wraps(func)
    def wrapper(*args: object, **kwargs: object) -> object:
        try:
            _check_finite(kwargs)
            return func(*args, **kwargs)
        except (InputError, FileNotFoundError, NotADirectoryError, IsADirectoryError) as exc:
            message = str(exc) or exc.__class__.__name__
            if isinstance(exc, OSError) and exc.filename and str(exc.filename) not in message:
                message = f"{exc.filename}: {message}"
            typer.echo(f"error: {message}", err=True)
            raise typer.Exit(code=2) from None

    return wrapper  # type: ignore[return-value]


def _check_finite(options: dict[str, object]) -> None:
    """Every float option must be a number: typer's ``min=``/``max=`` let ``nan`` through (it compares False)."""
    for name, value in options.items():
        if isinstance(value, float) and not math.isfinite(value):
            raise InputError(f"--{name.replace('_', '-')}: must be a finite number, got {value}")


class OneLineErrorGroup(TyperGroup):
    """The root command group: a usage error anywhere below it ends as ONE line ``error: ...`` and exit code 2.

    Usage errors are what typer finds before a command runs (a value that is not one of the choices, a number
    out of range, an unknown option or command, a missing argument) and ``typer.BadParameter`` raised by a
    command; typer would print them as a usage box. Sub-commands are parsed and run inside the root's
    ``invoke``, so the root's ``make_context`` (its own options) and ``invoke`` (everything below) see them all.
    A group called without arguments still prints its help.
    """

    def make_context(self, info_name: str | None, args: list[str], parent: Any = None, **extra: Any) -> Any:
        with _one_line_usage_errors():
            return super().make_context(info_name, args, parent=parent, **extra)

    def invoke(self, ctx: Any) -> Any:
        with _one_line_usage_errors():
            return super().invoke(ctx)


@contextmanager
def _one_line_usage_errors() -> Iterator[None]:
    try:
        yield
    except NoArgsIsHelpError:  # `clone`, `clone pose`: the help is the answer
        raise
    except UsageError as exc:
        message = " ".join(exc.format_message().split())  # one line, whatever the message holds
        typer.echo(f"error: {message}", err=True)
        raise typer.Exit(code=2) from None


def setup_logging(verbose: bool) -> None:
    logging.basicConfig(
        level=logging.DEBUG if verbose else logging.WARNING,
        format="%(levelname)s %(name)s: %(message)s",
        stream=sys.stderr,
    )


# --device is free text (cuda:N), not a choice: resolve_device_option checks it.
DEVICE_HELP = "auto | cpu | cuda | cuda:N"
MAX_THREADS = 1024  # --threads of every command
MAX_CLIP_FRAMES = 100_000  # frames of a case or clip a retarget command generates (eval, eval-cloning, interpolate)

# Options several commands that read the motion world or compare checkpoints share.
CompareOption = Annotated[
    list[str] | None, typer.Option("--compare", help="Another checkpoint as NAME=PATH (repeatable).")
]
# --mocap and --weights of the commands that build the motion world and score our network on it.
MocapOption = Annotated[Path, typer.Option("--mocap", help="Motion-capture folder the motion world is built from.")]
OurWeightsOption = Annotated[
    Path | None, typer.Option("--weights", help="Our checkpoint (default: the shipped weights).")
]
WorldSeedOption = Annotated[
    int, typer.Option("--world-seed", help="Seed of the world (its split and characters); training's --seed.")
]
WorldCacheOption = Annotated[
    Path | None, typer.Option("--cache", help="World cache folder (default: ~/.cache/clone2d/world).")
]

MAX_REFINE_STEPS = 1000
# --refine-steps of the commands that retarget a driver onto a reference (drive, report, cartoon).
RefineStepsOption = Annotated[
    int | None,
    typer.Option("--refine-steps", help="Retargeting: gradient steps that refine each driver window's motion code "
                 "before it is decoded onto the reference (default: 30; fewer are faster; 0: the network alone)."),
]


def named_checkpoints(items: list[str] | None, taken: tuple[str, ...] = ()) -> dict[str, Path]:
    """``--compare NAME=PATH`` values by name; InputError for a malformed one or a name in ``taken`` or repeated."""
    named: dict[str, Path] = {}
    for item in items or []:
        name, sep, path = item.partition("=")
        if not sep or not name.strip() or not path:
            raise InputError(f"--compare {item!r}: expected NAME=PATH")
        if name.strip() in (*taken, *named):
            raise InputError(f"--compare {name.strip()}: that row name is taken; choose another")
        named[name.strip()] = Path(path)
    return named


def training_device(spec: str, threads: int | None = None):  # -> torch.device
    """:func:`resolve_device_option` for a trainer that may run under torchrun: the processes of one machine then
    share its free cores unless ``--threads`` is given. InputError on a malformed torchrun environment."""
    from retarget.runtime import free_cores
    from retarget.training import distributed

    try:
        launch = distributed.from_environment()
    except ValueError as exc:
        raise InputError(str(exc)) from None
    if launch is not None and threads is None:
        threads = distributed.cpu_threads(launch, free_cores(now=False))  # the siblings would count as busy
    return resolve_device_option(spec, threads)


def resolve_device_option(spec: str, threads: int | None = None):  # -> torch.device
    """Resolve ``--device`` at the command-line edge (InputError on a bad one); on CPU set torch's threads.

    Library functions take the resulting ``torch.device``; none of them resolves "auto" itself.
    """
    from retarget.runtime import configure_threads, resolve_device

    try:
        device = resolve_device(spec)
    except ValueError as exc:
        raise InputError(str(exc)) from None
    if device.type == "cpu":
        configure_threads(threads)
    return device


AudioOption = Annotated[str, typer.Option(
    "--audio", help="The output's sound: auto: the driver's, when it is a video with sound; none: silent; or "
    "FILE: that file's sound, from its start, cut to the output's length.")]
