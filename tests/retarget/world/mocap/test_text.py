"""Reading a mocap file's text, plain or gzip."""

from __future__ import annotations

import gzip
from pathlib import Path

import pytest

from pose_io.errors import InputError
from retarget.world.mocap import read_text


def test_gzip_is_recognised_by_content_not_name(tmp_path: Path) -> None:
    packed = tmp_path / "clip.bvh"
    packed.write_bytes(gzip.compress(b"HIERARCHY\n"))
    plain = tmp_path / "clip.bvh.gz"
    plain.write_text("HIERARCHY\n")
    assert read_text(packed) == read_text(plain) == "HIERARCHY\n"


def test_latin1_fallback(tmp_path: Path) -> None:
    path = tmp_path / "old.asf"
    path.write_bytes(b":name Jos\xe9\n")
    assert read_text(path) == ":name Jos\u00e9\n"


def test_folder_is_a_clear_error(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="is a folder"):
        read_text(tmp_path)
