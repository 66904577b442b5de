"""Entry point of the `clone` command.

Each verb group lives in its own module and registers itself here. Nothing heavy is imported at
module level, so `clone --help` stays fast.
"""

from __future__ import annotations

import typer

from clone import __version__
from clone.cli.common import setup_logging

app = typer.Typer(
    name="clone",
    help="2D performance cloning: move a driver's motion onto a reference person, then render them.",
    no_args_is_help=True,
    add_completion=False,
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


# Verb groups register below, one line each, as they land.
from clone.cli.pose import pose_app  # noqa: E402
app.add_typer(pose_app, name="pose")
from clone.cli.retarget import retarget_app  # noqa: E402
app.add_typer(retarget_app, name="retarget")
from clone.cli.world import world_app  # noqa: E402
app.add_typer(world_app, name="world")
from clone.cli.synth import synth_app  # noqa: E402
app.add_typer(synth_app, name="synth")
from clone.cli import cloning  # noqa: E402
app.command("train-ref")(cloning.train_ref); app.command("drive")(cloning.drive)  # noqa: E702
from clone.cli.report import report_command  # noqa: E402
app.command("report")(report_command)
from clone.cli.demo import demo_command  # noqa: E402
app.command("demo")(demo_command)


def main() -> None:
    app()
