"""Choices are types: every closed set of option values is an enum that `clone` lists in --help, completes in the
shell and checks before a command runs; a bad value, like any usage error, is one ``error:`` line and exit 2."""

from __future__ import annotations

import os
import subprocess
import sys
from enum import Enum
from itertools import takewhile
from pathlib import Path

import pytest
from typer.testing import CliRunner

from clone.cli import choices
from clone.cli.main import app

WIDE = {"COLUMNS": "200"}  # rich would cut long choice lists at the default 80 columns

# (command line up to the option, the option, its enum); the required arguments come first so that the bad
# value is the only problem.
CHOICE_OPTIONS = [
    (["drive", "{tmp}/drv", "--out", "{tmp}/o.mp4"], "--method", choices.Method),
    (["drive", "{tmp}/drv", "--out", "{tmp}/o.mp4"], "--stage", choices.StageMode),
    (["report", "{tmp}/drv", "--out", "{tmp}/rep"], "--stage", choices.StageMode),
    (["train-ref", "{tmp}/poses", "{tmp}/frames", "--out", "{tmp}/m.pt"], "--canvas", choices.CanvasMode),
    (["train-ref", "{tmp}/poses", "{tmp}/frames", "--out", "{tmp}/m.pt"], "--align", choices.Align),
    (["retarget", "train", "--mocap", "{tmp}/mocap", "--out", "{tmp}/r.pt"], "--variant", choices.Variant),
    (["retarget", "train", "--mocap", "{tmp}/mocap", "--out", "{tmp}/r.pt"], "--ablation", choices.Ablation),
    (["retarget", "eval", "--mocap", "{tmp}/mocap", "--out", "{tmp}/eval"], "--split", choices.Split),
    (["pose", "info", "{tmp}/poses"], "--format", choices.PoseFormat),
    (["pose", "convert", "{tmp}/poses", "{tmp}/out.npz"], "--to-layout", choices.Layout),
    (["pose", "convert", "{tmp}/poses", "{tmp}/out.npz"], "--to", choices.OutputFormat),
]
IDS = [" ".join([*takewhile(lambda a: not a.startswith(("-", "{")), args), opt]) for args, opt, _ in CHOICE_OPTIONS]


def invoke(*args: str, env: dict[str, str] | None = None):
    return CliRunner().invoke(app, list(args), env=env)


def one_error_line(result) -> str:
    assert result.exit_code == 2, result.output
    lines = [line for line in result.output.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), result.output
    return lines[0]


def values(enum: type[Enum]) -> list[str]:
    return [member.value for member in enum]


@pytest.mark.parametrize("args, option, enum", CHOICE_OPTIONS, ids=IDS)
def test_help_lists_the_choices(args, option, enum):
    command = takewhile(lambda a: not a.startswith(("-", "{")), args)
    result = invoke(*command, "--help", env=WIDE)
    assert result.exit_code == 0, result.output
    line = next(line for line in result.output.splitlines() if f" {option} " in line)
    assert f"<{'|'.join(values(enum))}>" in line


@pytest.mark.parametrize("args, option, enum", CHOICE_OPTIONS, ids=IDS)
def test_a_bad_choice_is_one_error_line_naming_the_valid_ones(tmp_path: Path, args, option, enum):
    args = [a.replace("{tmp}", str(tmp_path)) for a in args]
    line = one_error_line(invoke(*args, option, "bogus"))
    assert option in line and "'bogus'" in line and f"valid: {', '.join(values(enum))}" in line
    assert list(tmp_path.iterdir()) == []  # rejected before the command ran


def test_a_good_choice_reaches_the_library_as_its_plain_name(tmp_path: Path, monkeypatch):
    import clone.drive.run
    from pose_io.errors import InputError

    seen = {}

    def fake_drive(*args, **kwargs):
        seen.update(kwargs)
        raise InputError("stop here")

    monkeypatch.setattr(clone.drive.run, "drive", fake_drive)
    line = one_error_line(invoke("drive", str(tmp_path / "drv"), "--out", str(tmp_path / "o.mp4"),
                                 "--method", "global-scale", "--device", "cpu"))
    assert line == "error: stop here"
    assert seen["method"] == "global-scale" and type(seen["method"]) is str  # what DriveResult and files keep


@pytest.mark.parametrize(
    "args, message",
    [
        (["retarget", "train", "--mocap", "m", "--out", "r.pt", "--threads", "0"], "'--threads'"),
        (["pose", "convert", "a", "b", "--max-gap", "-1"], "No such option: --max-gap"),
        (["drive"], "Missing argument"),
        (["bogus"], "No such command 'bogus'"),
        (["--bogus"], "No such option: --bogus"),
    ],
)
def test_other_usage_errors_are_one_line_too(args, message):
    assert message in one_error_line(invoke(*args))


def test_help_still_works_and_no_arguments_show_it():
    for args in (["--help"], ["-h"], ["pose", "--help"], ["retarget", "train", "--help"]):
        result = invoke(*args)
        assert result.exit_code == 0 and "Usage" in result.output, (args, result.output)
    for args in ([], ["retarget"]):
        result = invoke(*args)
        assert "Usage" in result.output and "Commands" in result.output and "error:" not in result.output


def test_shell_completion_is_on_and_completes_the_choices():
    result = invoke("--help", env=WIDE)
    assert "--install-completion" in result.output and "--show-completion" in result.output
    # Typer's --show-completion is a flag that asks shellingham for the parent shell, so "bash" would be ignored
    # when the tests run without a shell above them (CI, a background job); typer's own switch makes it take the name.
    env = {**os.environ, "_TYPER_COMPLETE_TEST_DISABLE_SHELL_DETECTION": "1"}
    script = subprocess.run([str(Path(sys.executable).parent / "clone"), "--show-completion", "bash"],
                            capture_output=True, text=True, check=False, env=env)
    assert script.returncode == 0 and "_CLONE_COMPLETE" in script.stdout, script.stderr
    completion = {"_CLONE_COMPLETE": "complete_bash", "COMP_WORDS": "clone drive d.npz --method ", "COMP_CWORD": "4"}
    result = invoke(env=completion)
    assert result.exit_code == 0 and result.output.split() == values(choices.Method)


# The command line keeps copies of the library's enums whose modules import torch or OpenCV; they must agree.
def test_the_library_registries_match_the_enums():
    """The enums are built from light modules; the registries that interpret them must hold the same names."""
    from clone.drive import poses as drive
    from clone.model import canvas
    from retarget.network import model
    from retarget.training import losses
    from retarget.world.config import SPLITS

    assert set(values(choices.Split)) < set(SPLITS)
    assert list(model.VARIANTS) == values(model.Variant) and list(losses.ABLATIONS) == values(losses.Ablation)
    assert drive.METHODS == tuple(values(drive.Method)) and canvas.CANVAS_MODES == tuple(values(canvas.CanvasMode))
    assert model.variant_config(model.Variant.VIEW) == model.variant_config("view")
    assert losses.ablation_config(losses.Ablation.NO_TRIPLET) == losses.ablation_config("no-triplet")


def test_building_the_app_imports_neither_torch_nor_opencv():
    """Why the copies exist: typer reads every option type for `clone --help` and each completion request."""
    code = ("import sys; from typer.main import get_command; from clone.cli.main import app; get_command(app); "
            "heavy = [m for m in ('torch', 'cv2') if m in sys.modules]; assert not heavy, heavy")
    subprocess.run([sys.executable, "-c", code], check=True, cwd=Path(__file__).resolve().parents[3])
