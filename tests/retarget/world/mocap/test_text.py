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


def test_text_beyond_the_cap_is_one_clear_error(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from retarget.world.mocap import text

    monkeypatch.setattr(text, "MAX_TEXT_BYTES", 1000)
    bomb = tmp_path / "bomb.bvh.gz"
    bomb.write_bytes(gzip.compress(b"0 " * 5000))  # 10 kB of text in a ~60-byte file
    assert bomb.stat().st_size < 1000
    with pytest.raises(InputError, match="more than 0 MB of text"):
        read_text(bomb)
    big = tmp_path / "big.bvh"
    big.write_text("0 " * 600)
    with pytest.raises(InputError, match="not a motion-capture file"):
        read_text(big)
    small = tmp_path / "small.bvh.gz"
    small.write_bytes(gzip.compress(b"0 " * 400))  # within the cap, compressed or not
    assert read_text(small) == "0 " * 400
