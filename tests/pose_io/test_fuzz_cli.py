"""Fuzzing ``clone pose info`` and ``clone pose convert`` (typer's CliRunner) on generated files and options.

Every case ends in exit code 0, or exit code 2 with exactly one ``error:`` line on stderr and no traceback;
a successful convert leaves a readable output and no temporary file next to it. The command line lives in
``clone``, but what it reads and checks is pose_io's, so the fuzzing lives next to the readers' own.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import event, given
from hypothesis import strategies as st
from typer.testing import CliRunner

from clone.cli.main import app
from pose_io import read_track
from tests.pose_io.fuzzing import HOSTILE_NUMBERS, fast_and_slow
from tests.pose_io.test_fuzz_tables import assert_sane, csv_texts, npy_bytes, npz_bytes

runner = CliRunner()

_SIZES = ["640x480", "16x16", "16384x16384", "16385x16", "100000x100000", "0x10", "12", "axb", "9" * 30 + "x9", ""]
_LAYOUT_NAMES = ["body25", "body15", "coco18", "coco17", "mediapipe33", "bogus"]


@st.composite
def openpose_folder(draw: st.DrawFn) -> dict[str, bytes]:
    """File name -> bytes of a small OpenPose folder: plausible people, hostile values, a sidecar or junk."""
    n = draw(st.sampled_from([25, 18, 15]))
    rng = np.random.default_rng(draw(st.integers(0, 999)))
    files: dict[str, bytes] = {}
    for t in range(draw(st.integers(1, 4))):
        people = []
        for _ in range(draw(st.integers(0, 2))):
            xyc = np.c_[rng.uniform(0, 500, (n, 2)), rng.uniform(0.1, 1, n)].ravel().tolist()
            if draw(st.booleans()):
                xyc[draw(st.integers(0, len(xyc) - 1))] = float(draw(st.sampled_from(HOSTILE_NUMBERS[4:16])))
            people.append({"pose_keypoints_2d": xyc})
        files[f"c_{t:012d}_keypoints.json"] = json.dumps({"version": 1.3, "people": people}).encode()
    extra = draw(st.sampled_from(["none", "none", "sidecar", "junk", "undecodable"]))
    if extra == "sidecar":
        files["clone2d_track.json"] = json.dumps({
            "kind": "clone2d-openpose-folder", "fps": draw(st.sampled_from([30, 0, 1e9, 1000, 10**30])),
            "image_size": draw(st.sampled_from([[640, 480], [100000, 100000], [0, 5], [16384, 1]])),
            "layout": {25: "body25", 18: "coco18", 15: "body15"}[n]}).encode()
    elif extra == "junk":
        files["c_000000000099_keypoints.json"] = draw(st.binary(max_size=30))
    elif extra == "undecodable":
        files["c_000000000099_keypoints.json"] = b"\xff\xfe{\x00"
    return files


_sources = (
    st.tuples(st.just(".npz"), npz_bytes())
    | st.tuples(st.just(".csv"), csv_texts().map(lambda t: t.encode("utf-8", "surrogatepass")))
    | st.tuples(st.just(".npy"), npy_bytes())
    | st.tuples(st.just(""), openpose_folder())
)


@st.composite
def command(draw: st.DrawFn) -> list[str]:
    """The options after ``pose info IN`` or ``pose convert IN OUT`` (the verb is the first element)."""
    verb = draw(st.sampled_from(["info", "convert", "convert"]))
    args: list[str] = [verb]
    options = {
        "--size": st.sampled_from(_SIZES),
        "--in-fps": st.sampled_from(HOSTILE_NUMBERS[:20] + ["30", "abc"]),
        "--person": st.sampled_from(["0", "1", "5", "-1"]),
    }
    if verb == "convert":
        options.update({
            "--fps": st.sampled_from(["10", "60", "1000", "1001", "1e9", "0", "-3", "nan", "0.01", "1e-9"]),
            "--smooth": st.sampled_from(["0", "2", "1e12", "-1", "nan"]),
            "--fill-gaps": st.sampled_from(["0", "3", "1000000000", "-2"]),
            "--to-layout": st.sampled_from(_LAYOUT_NAMES),
        })
    for name in draw(st.lists(st.sampled_from(sorted(options)), max_size=3, unique=True)):
        args += [name, draw(options[name])]
    return args


def _cli_case(tmp_path_factory: pytest.TempPathFactory, source: tuple[str, object], cmd: list[str],
              out_suffix: str) -> None:
    tmp = tmp_path_factory.mktemp("cli")
    suffix, content = source
    src = tmp / f"in{suffix}"
    if isinstance(content, dict):
        src.mkdir()
        for name, data in content.items():
            (src / name).write_bytes(data)
    else:
        src.write_bytes(content)
    dst = tmp / f"out{out_suffix}"
    verb, options = cmd[0], cmd[1:]
    args = ["pose", verb, str(src)] + ([str(dst)] if verb == "convert" else []) + options
    result = runner.invoke(app, args)
    assert result.exit_code in (0, 2), (args, result.output, repr(result.exception))
    assert "Traceback" not in result.output, (args, result.output)
    if result.exit_code == 2:
        errors = [line for line in result.stderr.splitlines() if line.startswith("error:")]
        assert len(errors) == 1, (args, result.stderr)
        event(f"{verb}: error")
    else:
        event(f"{verb}: ok")
        if verb == "convert":
            assert_sane(read_track(dst))
    leftovers = [p.name for p in tmp.iterdir() if p.name.startswith(".")]
    assert not leftovers, (args, leftovers)


test_pose_cli_fuzz, test_pose_cli_fuzz_slow = fast_and_slow(
    lambda: given(source=_sources, cmd=command(), out_suffix=st.sampled_from([".csv", ".npz", "", ".json"]))(
        _cli_case), fast=60)
