"""CLI fuzz: argv built from a command's options with random values ends in success or ONE error line, never a
traceback. A few hundred examples by default; ``-m slow`` runs more than 10,000."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from clone.cli.main import app
from tests.bad_inputs import builders as b
from tests.bad_inputs.test_corpus import check_one_error_line

# Commands that end fast whatever their options: (argv prefix, options it takes, builders of its files).
COMMANDS = {
    "pose info": (["pose", "info", "{t}/poses.npz"], ["--in-fps", "--person", "--size", "--format"], [b.poses_npz]),
    "pose convert": (["pose", "convert", "{t}/poses.npz", "{t}/out/new.npz"],
                     ["--fill-gaps", "--smooth", "--fps", "--in-fps", "--person", "--to", "--to-layout"],
                     [b.poses_npz]),
    "synth render": (["synth", "render", "{t}/bad.bvh", "--out", "{t}/synth"],
                     ["--yaw", "--pitch", "--size", "--start", "--frames", "--fps", "--character"], [b.bad_motion]),
    "world build": (["world", "build", "--mocap", "{t}/mocap", "--cache", "{t}/cache"],
                    ["--fps", "--train-characters", "--val-characters", "--test-characters", "--window", "--stride",
                     "--seed"], [b.mocap_empty]),
    "train-ref": (["train-ref", "{t}/poses.npz", "{t}/missing_frames", "--out", "{t}/m.pt", "--device", "cpu"],
                  ["--size", "--steps", "--minutes", "--batch-size", "--threads", "--canvas", "--align"],
                  [b.poses_npz]),
    "drive": (["drive", "{t}/poses.npz", "--out", "{t}/o.mp4", "--model", "{t}/foreign.pt", "--device", "cpu"],
              ["--max-gap", "--threads", "--method", "--stage", "--poses-out"], [b.poses_npz, b.foreign_pt]),
}

numbers = st.one_of(
    st.integers(min_value=-(10**12), max_value=10**12).map(str),
    st.floats(allow_nan=True, allow_infinity=True).map(lambda v: repr(v) if math.isfinite(v) else str(v)),
    st.sampled_from(["0", "-0", "1e308", "nan", "-inf", "0x10", "1_000", "", " ", "9" * 40]),
)
values = st.one_of(numbers, st.text(st.characters(blacklist_categories=("Cs",), blacklist_characters="\x00"),
                                    max_size=12), st.sampled_from(["640x480", "0x0", "body15", "npz", "trim"]))


def argv_for(command: str):
    prefix, opts, _ = COMMANDS[command]
    return st.lists(st.tuples(st.sampled_from(opts), values), min_size=1, max_size=3).map(
        lambda pairs: [*prefix, *[x for pair in pairs for x in pair]])


@st.composite
def cases(draw):
    command = draw(st.sampled_from(sorted(COMMANDS)))
    return command, draw(argv_for(command))


def _check(tmp_root: Path, command: str, argv: list[str]) -> None:
    folder = tmp_root / command.replace(" ", "_")
    if not folder.exists():
        folder.mkdir()
        for build in COMMANDS[command][2]:
            build(folder)
    result = CliRunner().invoke(app, [a.replace("{t}", str(folder)) for a in argv])
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception
    assert result.exit_code in (0, 2), (argv, result.output)
    if result.exit_code == 2:
        check_one_error_line(result.exit_code, result.stderr, result.stdout)


def _fuzz(max_examples: int):
    @settings(max_examples=max_examples, deadline=None, derandomize=True,
              suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
    @given(case=cases())
    def test(tmp_path_factory: pytest.TempPathFactory, monkeypatch: pytest.MonkeyPatch, case) -> None:
        command, argv = case
        root = tmp_path_factory.getbasetemp() / "fuzz"
        root.mkdir(exist_ok=True)
        monkeypatch.chdir(root)
        monkeypatch.setenv("OMP_NUM_THREADS", "1")
        _check(root, command, argv)

    return test


test_cli_fuzz = _fuzz(300)
test_cli_fuzz_long = pytest.mark.slow(_fuzz(10_000))
