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


def test_sigterm_exits_128_plus_15_even_when_an_import_turns_it_into_another_error(monkeypatch):
    import signal

    import pytest

    from clone.cli import main as cli_main

    def import_interrupted() -> None:
        try:
            cli_main._terminate(signal.SIGTERM, None)  # the handler, as if the signal arrived here
        except SystemExit:
            raise ImportError("initialization failed") from None  # what onnxruntime's import makes of it

    monkeypatch.setattr(cli_main, "app", import_interrupted)
    monkeypatch.setattr(cli_main, "_terminated_by", [])
    previous = signal.getsignal(signal.SIGTERM)
    try:
        with pytest.raises(SystemExit) as ended:
            cli_main.main()
        assert ended.value.code == 128 + signal.SIGTERM
        monkeypatch.setattr(cli_main, "_terminated_by", [])
        monkeypatch.setattr(cli_main, "app", lambda: (_ for _ in ()).throw(ImportError("a real one")))
        with pytest.raises(ImportError, match="a real one"):  # without a signal, errors stay what they are
            cli_main.main()
    finally:
        signal.signal(signal.SIGTERM, previous)
