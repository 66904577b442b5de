from typer.testing import CliRunner

from clone.cli.main import app

WIDE = {"COLUMNS": "200"}


def test_help_and_version():
    runner = CliRunner()
    result = runner.invoke(app, ["--help"])
    assert result.exit_code == 0
    assert "clone" in result.output
    result = runner.invoke(app, ["--version"])
    assert result.exit_code == 0 and "clone2d" in result.output


def _help_words(*args: str) -> set[str]:
    result = CliRunner().invoke(app, [*args, "--help"], env=WIDE)
    assert result.exit_code == 0, result.output
    return set(result.output.replace("│", " ").split())


def test_help_lists_every_command_and_every_group_lists_its_commands():
    root = _help_words()
    commands = [info.name for info in app.registered_commands]
    groups = {info.name: [c.name for c in info.typer_instance.registered_commands] for info in app.registered_groups}
    assert commands and groups
    for name in [*commands, *groups]:
        assert name in root, f"`clone --help` does not list {name}"
    for group, subcommands in groups.items():
        assert subcommands and None not in subcommands, group
        listed = _help_words(group)
        for name in subcommands:
            assert name in listed, f"`clone {group} --help` does not list {name}"
            assert CliRunner().invoke(app, [group, name, "--help"]).exit_code == 0, (group, name)
