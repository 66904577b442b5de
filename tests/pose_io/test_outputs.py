"""pose_io.outputs: the checks every command runs on its outputs and on the numbers its options scale."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from pose_io.atomic import check_free_space
from pose_io.errors import InputError
from pose_io.outputs import FOLDER, check_number, check_output


def test_a_new_file_with_a_good_suffix_passes(tmp_path: Path) -> None:
    assert check_output(tmp_path / "new" / "out.mp4", "--out", suffixes=(".mp4",)) == tmp_path / "new" / "out.mp4"
    assert not list(tmp_path.iterdir()) or [p.name for p in tmp_path.iterdir()] == []  # the probe is gone


@pytest.mark.parametrize("name, suffixes, message", [
    ("result", (".mp4",), "unsupported type (no suffix)"),
    ("preview.txt", (".mp4",), "unsupported type .txt"),
    ("poses.json", (FOLDER, ".npz", ".csv"), "use .npz or .csv or a folder"),
])
def test_wrong_suffixes_name_the_good_ones(tmp_path: Path, name: str, suffixes, message: str) -> None:
    with pytest.raises(InputError, match=message.replace("(", r"\(").replace(")", r"\)")):
        check_output(tmp_path / name, "--out", suffixes=suffixes)


def test_an_existing_folder_is_not_a_video(tmp_path: Path) -> None:
    (tmp_path / "v.mp4").mkdir()
    with pytest.raises(InputError, match="is a folder"):
        check_output(tmp_path / "v.mp4", "--out", suffixes=(".mp4",), overwrite=True)


def test_existing_outputs_need_overwrite(tmp_path: Path) -> None:
    (tmp_path / "o.npz").write_bytes(b"x")
    with pytest.raises(InputError, match="already exists"):
        check_output(tmp_path / "o.npz", "--out", suffixes=(FOLDER, ".npz"))
    check_output(tmp_path / "o.npz", "--out", suffixes=(FOLDER, ".npz"), overwrite=True)
    check_output(tmp_path / "o.npz", "--out", replaceable=True)
    (tmp_path / "d").mkdir()
    check_output(tmp_path / "d", "--out", suffixes=(FOLDER,), overwrite=True)


def test_unwritable_locations_fail_first(tmp_path: Path) -> None:
    (tmp_path / "blocker").write_text("a file")
    with pytest.raises(InputError, match="is not a folder"):
        check_output(tmp_path / "blocker" / "o.mp4", "--out", suffixes=(".mp4",))
    if Path("/proc").is_dir():  # writable by nobody, root included
        with pytest.raises(InputError, match="cannot write"):
            check_output(Path("/proc/o.mp4"), "--out", suffixes=(".mp4",))


@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf])
def test_numbers_must_be_finite(value: float) -> None:
    with pytest.raises(InputError, match="finite"):
        check_number("--yaw", value)


def test_number_ranges() -> None:
    check_number("--size", 32, 32, 1024)
    check_number("--steps", None, 1)
    with pytest.raises(InputError, match=">= 32 and <= 1024, got 65536"):
        check_number("--size", 65536, 32, 1024)
    with pytest.raises(InputError, match="> 0"):
        check_number("--minutes", 0.0, 0, low_open=True)


def test_free_space(tmp_path: Path) -> None:
    check_free_space(tmp_path, 1 << 20, "a small cache")
    with pytest.raises(InputError, match="needs .* GiB"):
        check_free_space(tmp_path, 1 << 60, "a frame cache of 1000 frames at 65536x65536")
