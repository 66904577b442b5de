"""The `clone` command line (typer). Sub-command modules import heavy libraries inside their commands."""
