from typer.testing import CliRunner

from clone.cli.main import app


def test_help_and_version():
    runner = CliRunner()
    result = runner.invoke(app, ["--help"])
    assert result.exit_code == 0
    assert "clone" in result.output
    result = runner.invoke(app, ["--version"])
    assert result.exit_code == 0 and "clone2d" in result.output
