"""Entry point of the `clone` command.

Each verb group lives in its own module and registers itself here. Nothing heavy is imported at
module level, so `clone --help` and shell completion (`clone --install-completion`) stay fast.

Every user error ends as one line ``error: ...`` and exit code 2: the library's InputError through
``user_errors`` on each command, typer's usage errors (a bad choice, a number out of range, an unknown option)
through the root group, ``OneLineErrorGroup``.
"""

from __future__ import annotations

import typer

from clone import __version__
from clone.cli import cloning
from clone.cli.cartoon import cartoon_command
from clone.cli.common import OneLineErrorGroup, setup_logging
from clone.cli.demo import demo_command
from clone.cli.pose import pose_app
from clone.cli.prior import train_prior_command
from clone.cli.report import report_command
from clone.cli.retarget import retarget_app
from clone.cli.search import search_app
from clone.cli.synth import synth_app
from clone.cli.world import world_app

app = typer.Typer(
    name="clone",
    help="2D performance cloning: move a driver's motion onto a reference person, then render them.",
    cls=OneLineErrorGroup,
    no_args_is_help=True,
    add_completion=True,
    pretty_exceptions_enable=False,
    context_settings={"help_option_names": ["-h", "--help"]},
)


def _version(value: bool) -> None:
    if value:
        typer.echo(f"clone2d {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    verbose: bool = typer.Option(False, "--verbose", "-v", help="Log what the library does."),
    version: bool = typer.Option(False, "--version", callback=_version, is_eager=True, help="Print the version."),
) -> None:
    setup_logging(verbose)


# The command groups, in the order `clone --help` lists them (each module imports its heavy libraries inside its
# commands, so registering them here keeps `clone --help` fast).
app.command("train-ref")(cloning.train_ref)
app.command("train-prior")(train_prior_command)
app.command("drive")(cloning.drive)
app.command("strip")(cloning.strip)
app.command("report")(report_command)
app.command("demo")(demo_command)
app.command("cartoon")(cartoon_command)
app.add_typer(pose_app, name="pose")
app.add_typer(retarget_app, name="retarget")
app.add_typer(world_app, name="world")
app.add_typer(synth_app, name="synth")
app.add_typer(search_app, name="search")


_terminated_by: list[int] = []  # the signal _terminate handled, if any


def _terminate(signum: int, frame: object) -> None:
    """SIGTERM ends the command as Ctrl-C does: unwinding, so every atomic writer's ``finally`` removes its temp file.

    The second SIGTERM kills at once (the default action is back).
    """
    import signal

    _terminated_by.append(signum)
    signal.signal(signum, signal.SIG_DFL)
    raise SystemExit(128 + signum)


def _quiet_library_warnings() -> None:
    """Users see our one-line errors and our own warnings, not the libraries' notes meant for developers."""
    import warnings

    # torch.load's pickle notice; we load with weights_only=True and say so when a file is foreign.
    warnings.filterwarnings("ignore", category=FutureWarning, module=r"torch(\.|$)")
    warnings.filterwarnings("ignore", message=r".*weights_only.*")
    warnings.filterwarnings("ignore", message=r".*TypedStorage is deprecated.*")
    # NumPy's "invalid value encountered", "Mean of empty slice", "overflow": bad input ends as one error line.
    warnings.filterwarnings("ignore", category=RuntimeWarning, module=r"numpy(\.|$)")
    warnings.filterwarnings("ignore", message=r"(invalid value|divide by zero|overflow) encountered",
                            category=RuntimeWarning)
    warnings.filterwarnings("ignore", message=r"(Mean of empty slice|Degrees of freedom <= 0)",
                            category=RuntimeWarning)


def main() -> None:
    """The `clone` console script."""
    import signal

    _quiet_library_warnings()
    if signal.getsignal(signal.SIGTERM) in (signal.SIG_DFL, None):
        signal.signal(signal.SIGTERM, _terminate)
    try:
        app()
    except BaseException:
        # The signal's SystemExit may surface as another exception: raised inside an extension module's
        # import (onnxruntime's becomes "ImportError: initialization failed"), it is the import that fails.
        if _terminated_by:
            raise SystemExit(128 + _terminated_by[0]) from None
        raise
