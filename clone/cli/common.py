"""Shared pieces of the command line: one-line errors, the console, device option parsing."""

from __future__ import annotations

import functools
import logging
import sys
from collections.abc import Callable
from typing import TypeVar

import typer
from rich.console import Console

from pose_io.errors import InputError

F = TypeVar("F", bound=Callable[..., object])

console = Console(stderr=True)


def user_errors(func: F) -> F:
    """Turn InputError (and missing files) into one ``error: ...`` line on stderr and exit code 2."""

    @functools.wraps(func)
    def wrapper(*args: object, **kwargs: object) -> object:
        try:
            return func(*args, **kwargs)
        except (InputError, FileNotFoundError, NotADirectoryError, IsADirectoryError) as exc:
            message = str(exc) or exc.__class__.__name__
            if isinstance(exc, OSError) and exc.filename and str(exc.filename) not in message:
                message = f"{exc.filename}: {message}"
            typer.echo(f"error: {message}", err=True)
            raise typer.Exit(code=2) from None

    return wrapper  # type: ignore[return-value]


def setup_logging(verbose: bool) -> None:
    logging.basicConfig(
        level=logging.DEBUG if verbose else logging.WARNING,
        format="%(levelname)s %(name)s: %(message)s",
        stream=sys.stderr,
    )


def device_option() -> str:
    return typer.Option("auto", "--device", help="auto | cpu | cuda | cuda:N")


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
