"""Our .npz reader parses headers without ast and reads each member once: the same arrays and verdicts as numpy."""

from __future__ import annotations

import io
import zipfile

import numpy as np
import pytest

from pose_io import InputError, read_track, write_track
from pose_io.read_arrays import _npz_entries, _parse_header

ARRAYS = {
    "float32 3-D": np.arange(120 * 15 * 2, dtype=np.float32).reshape(120, 15, 2) / 7,
    "float64 0-d": np.float64(29.97),
    "int64 pair": np.array([720, 480], dtype=np.int64),
    "big-endian": np.arange(12, dtype=">f4").reshape(3, 4),
    "fortran": np.asfortranarray(np.arange(12.0).reshape(3, 4)),
    "text 0-d": np.array("body25"),
    "bytes": np.array(b"body15"),
    "empty": np.zeros((0, 25, 2), dtype=np.float32),
    "long shape": np.zeros((1, 1, 1, 1, 1, 2), dtype=np.uint8),
}


def _npy_bytes(array: np.ndarray, version: tuple[int, int] | None = None) -> bytes:
    f = io.BytesIO()
    np.lib.format.write_array(f, np.asanyarray(array), version=version)
    return f.getvalue()


@pytest.mark.parametrize("name", sorted(ARRAYS))
@pytest.mark.parametrize("version", [None, (2, 0)])
def test_headers_parse_as_numpy_parses_them(name, version):
    raw = _npy_bytes(ARRAYS[name], version)
    expected_stream = io.BytesIO(raw)
    major = np.lib.format.read_magic(expected_stream)
    read = np.lib.format.read_array_header_1_0 if major == (1, 0) else np.lib.format.read_array_header_2_0
    expected = read(expected_stream)
    stream = io.BytesIO(raw)
    assert _parse_header(stream) == expected
    assert stream.tell() == expected_stream.tell()  # left at the data


@pytest.mark.parametrize(
    "header",
    [
        "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }",  # canonical, numpy's padding below
        "{'shape': (2, 3), 'fortran_order': False, 'descr': '<f4'}",  # another key order: numpy's parser
        "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3),   }",  # odd spacing: numpy's parser
        "{'descr': [('a', '<f4')], 'fortran_order': False, 'shape': (2,), }",  # structured: numpy's parser
        "{'descr': '<q9', 'fortran_order': False, 'shape': (2,), }",  # not a dtype: numpy's error
        "{'descr': '<f4', 'fortran_order': False, 'shape': (-2,), }",  # negative size: numpy's verdict
        "{'descr': '<f4', 'fortran_order': 1, 'shape': (2,), }",  # not a bool: numpy's error
        "not a dict at all",
    ],
)
def test_unusual_headers_get_numpy_verdicts(header):
    text = header.encode("latin1")
    text += b" " * (-(len(text) + 11) % 64) + b"\n"
    raw = b"\x93NUMPY\x01\x00" + len(text).to_bytes(2, "little") + text
    try:
        expected = ("ok", np.lib.format.read_array_header_1_0(io.BytesIO(raw[8:])))
    except Exception as exc:  # noqa: BLE001 - whatever numpy says, we say
        expected = ("error", type(exc), str(exc))
    try:
        got = ("ok", _parse_header(io.BytesIO(raw)))
    except Exception as exc:  # noqa: BLE001
        got = ("error", type(exc), str(exc))
    assert got == expected


@pytest.mark.parametrize("compression", [zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED])
def test_members_read_once_equal_np_load(tmp_path, compression):
    path = tmp_path / "a.npz"
    members = {"joints": ARRAYS["float32 3-D"], "confidence": ARRAYS["fortran"], "fps": ARRAYS["float64 0-d"],
               "image_size": ARRAYS["big-endian"], "layout": ARRAYS["text 0-d"]}  # fmt: skip
    with zipfile.ZipFile(path, "w", compression) as archive:
        for key, value in members.items():
            archive.writestr(f"{key}.npy", _npy_bytes(value))
    got = _npz_entries(path, tuple(members))
    with np.load(path) as expected:
        for key in members:
            assert got[key].dtype == expected[key].dtype and got[key].shape == expected[key].shape
            assert got[key].tobytes() == expected[key].tobytes()


def test_a_member_shorter_than_its_header_claims_is_an_input_error(tmp_path):
    path = tmp_path / "short.npz"
    raw = _npy_bytes(ARRAYS["float32 3-D"])
    with zipfile.ZipFile(path, "w") as archive:
        archive.writestr("joints.npy", raw[:-40])
        archive.writestr("confidence.npy", _npy_bytes(np.ones((120, 15), np.float32)))
    with pytest.raises(InputError, match="joints: truncated"):
        _npz_entries(path, ("joints", "confidence"))


def test_written_npz_is_stored_and_reads_back_bit_for_bit(tmp_path, walking_track):
    path = write_track(walking_track, tmp_path / "w.npz")
    with zipfile.ZipFile(path) as archive:
        assert {i.compress_type for i in archive.infolist()} == {zipfile.ZIP_STORED}
    back = read_track(path)
    assert back.joints.tobytes() == walking_track.joints.tobytes()
    assert back.confidence.tobytes() == walking_track.confidence.tobytes()
    assert (back.fps, back.image_size, back.layout) == (walking_track.fps, walking_track.image_size,
                                                        walking_track.layout)  # fmt: skip
