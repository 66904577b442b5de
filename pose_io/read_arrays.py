"""Readers of the table formats: our ``.npz``, plain ``.npy`` and ``.csv`` (documented in :mod:`pose_io.readers`).

Array headers are read before the data, so a file claiming an array larger than any allowed track
(or than the file itself) fails before memory is taken; every value is checked with
:func:`pose_io.limits.real_array` (real, finite or NaN, within float32 range). The CSV reader is linear
in the number of rows.
"""

from __future__ import annotations

import csv
import io
import itertools
import math
import re
import zipfile
from collections.abc import Iterator
from pathlib import Path
from typing import BinaryIO, TextIO

import numpy as np

from pose_io.errors import InputError
from pose_io.layouts import LAYOUTS, get_layout
from pose_io.limits import FLOAT32_MAX, MAX_FRAMES, check_fps, check_image_size, real_array
from pose_io.people import Detections
from pose_io.read_common import (
    check_confidence,
    frame_range,
    layout_from_joints,
    parse_size,
    require_file,
    short_error,
    single_person,
)

#: Largest array a table may hold: the longest allowed track of the largest layout, with confidences.
_MAX_VALUES = MAX_FRAMES * max(len(layout) for layout in LAYOUTS.values()) * 3
#: CSV rows converted at once; and how much of a CSV's top may be ``# key: value`` lines.
_CSV_CHUNK = 10_000
_MAX_META_LINES = 1_000
_MAX_META_CHARS = 10_000
_ZIP_ERRORS = (OSError, EOFError, zipfile.BadZipFile, zipfile.LargeZipFile, NotImplementedError, RuntimeError)

# ----------------------------------------------------------------------------------------------- .npy / .npz


# The header np.save writes (a dict literal padded with spaces), read without ``ast``; anything else goes to
# numpy's own parser, so what is accepted, and every error message, stays numpy's.
_NPY_HEADER = re.compile(r"\{'descr': '([<>|=]?[a-zA-Z]\d*)', 'fortran_order': (True|False), "
                         r"'shape': \(((?:\d+, )*\d+,?)?\), \} *\n")
_MAX_HEADER = 10_000  # numpy's max_header_size


def _parse_header(fp: BinaryIO) -> tuple[tuple[int, ...], bool, np.dtype]:
    """(shape, fortran order, dtype) of the .npy header at ``fp``, as numpy's ``read_array_header_*`` give."""
    version = np.lib.format.read_magic(fp)
    if version == (2, 0):
        return np.lib.format.read_array_header_2_0(fp)
    if version != (1, 0):
        raise ValueError(f"unsupported .npy format version {version}")
    length = fp.read(2)
    header = fp.read(int.from_bytes(length, "little")) if len(length) == 2 else b""
    match = _NPY_HEADER.fullmatch(header.decode("latin1")) if len(header) <= _MAX_HEADER else None
    if match:
        descr, fortran, dims = match.groups()
        try:
            return tuple(int(d) for d in dims.split(",") if d) if dims else (), fortran == "True", np.dtype(descr)
        except (TypeError, ValueError):
            pass
    return np.lib.format.read_array_header_1_0(io.BytesIO(length + header))  # numpy's verdict on the rest


def _header(fp: BinaryIO, available: int, what: str, kinds: str = "iuf") -> tuple[tuple[int, ...], bool, np.dtype]:
    """Shape, fortran order and dtype from an .npy header at ``fp``; InputError unless a real array that fits in
    ``available`` bytes.

    Args:
        fp: stream at the start of the .npy data (left at the start of the array's bytes).
        available: bytes of the stream, header included.
        what: how messages name the array.
        kinds: the dtype kinds allowed (numpy's ``dtype.kind`` letters).
    """
    try:
        shape, fortran, dtype = _parse_header(fp)
        header_end = fp.tell()
    except (ValueError, TypeError, SyntaxError, RecursionError, MemoryError, *_ZIP_ERRORS) as exc:
        raise InputError(f"{what}: cannot read as a .npy array ({short_error(exc)})") from None
    if dtype.kind not in kinds or dtype.hasobject:
        expected = "real numbers" if kinds == "iuf" else "text"
        raise InputError(f"{what}: must hold {expected}, got dtype {dtype}")
    count = math.prod(shape)
    if count > _MAX_VALUES:
        raise InputError(f"{what}: array of shape {shape} is larger than any allowed track")
    if count * dtype.itemsize > available - header_end:
        raise InputError(f"{what}: truncated: shape {shape} needs {count * dtype.itemsize:,} bytes, "
                         f"the file holds {max(available - header_end, 0):,}")
    return shape, fortran, dtype


def _load_npy(path: Path) -> np.ndarray:
    try:
        with open(path, "rb") as f:
            _header(f, path.stat().st_size, str(path))
        return np.load(path, allow_pickle=False)
    except InputError:
        raise
    except (OSError, ValueError, EOFError) as exc:
        raise InputError(f"{path}: cannot read as a .npy array ({short_error(exc)})") from None


def _npz_entries(path: Path, keys: tuple[str, ...]) -> dict[str, np.ndarray]:
    """The arrays ``keys`` of an .npz archive that holds them (headers checked before each is read)."""
    require_file(path)
    try:
        with zipfile.ZipFile(path) as archive:
            members = {n.removesuffix(".npy"): n for n in archive.namelist()}
            missing = [k for k in ("joints", "confidence") if k not in members]
            if missing:
                found = ", ".join(sorted(members))[:200] or "none"
                raise InputError(f"{path}: lacks {', '.join(missing)} (keys: {found})")
            out = {}
            for key in keys:
                if key not in members:
                    continue
                info = archive.getinfo(members[key])
                with archive.open(info) as f:
                    out[key] = _member_array(f, info.file_size, f"{path}: {key}", "US" if key == "layout" else "iuf")
            return out
    except InputError:
        raise
    except (ValueError, *_ZIP_ERRORS) as exc:
        raise InputError(f"{path}: cannot read as a .npz archive ({short_error(exc)})") from None


def _member_array(f: BinaryIO, available: int, what: str, kinds: str) -> np.ndarray:
    """The array of one archive member (read-only), its header checked first: ``np.lib.format.read_array``'s
    values, without parsing the header twice or reading the data in pieces."""
    shape, fortran, dtype = _header(f, available, what, kinds)
    count = math.prod(shape)
    size = count * dtype.itemsize
    data = f.read(size)
    if len(data) != size:
        raise ValueError(f"EOF: reading array data, expected {size} bytes got {len(data)}")
    flat = np.frombuffer(data, dtype=dtype, count=count) if size else np.empty(count, dtype=dtype)
    return flat.reshape(shape[::-1]).T if fortran else flat.reshape(shape)


def _numeric(arr: np.ndarray, what: str, ndim: int) -> np.ndarray:
    """``arr`` as float32 after the checks of :func:`real_array` and its number of dimensions."""
    if not isinstance(arr, np.ndarray) or arr.ndim != ndim or arr.dtype.kind not in "iuf":
        raise InputError(f"{what} must be a {ndim}-D numeric array, got shape {getattr(arr, 'shape', None)}")
    return real_array(arr, what).astype(np.float32)


def _scalar(arr: np.ndarray, what: str) -> float:
    if arr.dtype.kind not in "iuf" or arr.size != 1:
        raise InputError(f"{what} must be one real number, got dtype {arr.dtype} shape {arr.shape}")
    return float(real_array(arr, what).reshape(()))


def _image_size(arr: np.ndarray, what: str) -> tuple[int, int]:
    if arr.dtype.kind not in "iuf" or arr.shape != (2,):
        raise InputError(f"{what} must be (width, height), got dtype {arr.dtype} shape {arr.shape}")
    return check_image_size(tuple(arr.tolist()), what)


def _layout_name(arr: np.ndarray, what: str) -> str:
    if arr.dtype.kind not in "US" or arr.size != 1:
        raise InputError(f"{what} must be a layout name, got dtype {arr.dtype} shape {arr.shape}")
    value = arr.reshape(()).item()
    return value.decode("latin-1") if isinstance(value, bytes) else str(value)


def read_npy(path: Path) -> Detections:
    """A plain [T, J, 2] or [T, J, 3] array (layout from J)."""
    arr = _numeric(_load_npy(path), f"{path}: the array", 3)
    if arr.shape[2] not in (2, 3) or arr.shape[0] == 0:
        raise InputError(f"{path}: expected an array [T, J, 2] or [T, J, 3], got shape {arr.shape}")
    layout = layout_from_joints(arr.shape[1], path)
    conf = arr[..., 2] if arr.shape[2] == 3 else np.ones(arr.shape[:2], dtype=np.float32)
    check_confidence(conf, path)
    return Detections(single_person(arr[..., :2], conf), layout, single=True, source=str(path))


def read_npz(path: Path) -> Detections:
    """Our .npz: joints, confidence and optionally fps, image_size, layout."""
    entries = _npz_entries(path, ("joints", "confidence", "fps", "image_size", "layout"))
    joints = _numeric(entries["joints"], f"{path}: joints", 3)
    conf = _numeric(entries["confidence"], f"{path}: confidence", 2)
    fps = check_fps(_scalar(entries["fps"], f"{path}: fps"), f"{path}: fps") if "fps" in entries else None
    size = _image_size(entries["image_size"], f"{path}: image_size") if "image_size" in entries else None
    layout = _layout_name(entries["layout"], f"{path}: layout") if "layout" in entries else None
    if joints.shape[2] != 2 or joints.shape[0] == 0 or conf.shape != joints.shape[:2]:
        raise InputError(f"{path}: joints {joints.shape} / confidence {conf.shape}; expected [T, J, 2] / [T, J]")
    if layout is None:
        layout = layout_from_joints(joints.shape[1], path)
    elif layout not in LAYOUTS or len(LAYOUTS[layout]) != joints.shape[1]:
        raise InputError(f"{path}: layout {layout[:40]!r} does not fit {joints.shape[1]} joints")
    check_confidence(conf, path)
    return Detections(single_person(joints, conf), layout, fps=fps, image_size=size, single=True, source=str(path))


# ----------------------------------------------------------------------------------------------- CSV


def read_csv(path: Path) -> Detections:
    """``# key: value`` lines, a ``frame,<joint>_x,<joint>_y[,<joint>_c]`` header, one row per frame.

    The file is streamed row by row into float32 chunks, so memory stays near the size of the result.
    """
    require_file(path)
    try:
        with open(path, encoding="utf-8", newline="") as f:
            meta, first = _csv_meta(f)
            rows = (r for r in csv.reader(itertools.chain([first], f)) if r)
            header = [h.strip() for h in next(rows, [])]
            row_one = next(rows, None)
            if row_one is None:
                raise InputError(f"{path}: needs a header line and at least one frame row")
            if header[0] != "frame":
                raise InputError(f"{path}: the first column must be 'frame'")
            layout = _csv_layout(header[1:], meta.get("layout"), path)
            # [R] frame numbers, [R, C] float32
            numbers, cells = _csv_cells(itertools.chain([row_one], rows), len(header), path)
    except UnicodeDecodeError:
        raise InputError(f"{path}: not a UTF-8 text file") from None
    except csv.Error as exc:
        raise InputError(f"{path}: not a CSV table ({short_error(exc)})") from None
    except OSError as exc:
        raise InputError(f"{path}: cannot read ({short_error(exc)})") from None
    lay = get_layout(layout)
    col = {name: i for i, name in enumerate(header)}
    xy = cells[:, [[col[f"{n}_x"], col[f"{n}_y"]] for n in lay.joints]]  # [R, J, 2]
    c_cols = [col.get(f"{n}_c", -1) for n in lay.joints]
    rconf = np.where(np.array(c_cols) >= 0, cells[:, c_cols], 1.0)  # [R, J]; no _c column: confidence 1
    first_frame, count = frame_range(numbers, path, "frame")
    index = np.array([n - first_frame for n in numbers], dtype=np.int64)  # [R]
    joints = np.full((count, len(lay), 2), np.nan, dtype=np.float32)
    conf = np.zeros((count, len(lay)), dtype=np.float32)
    joints[index] = xy
    conf[index] = rconf
    check_confidence(conf, path)
    fps = check_fps(_meta_float(meta["fps"], f"{path}: fps"), f"{path}: fps") if "fps" in meta else None
    size = parse_size(meta["image_size"], f"{path}: image_size") if "image_size" in meta else None
    return Detections(single_person(joints, conf), layout, fps=fps, image_size=size, single=True, source=str(path))


def _csv_meta(f: TextIO) -> tuple[dict[str, str], str]:
    """The ``# key: value`` lines at the top of a CSV, and the first line after them ("" at the end)."""
    meta: dict[str, str] = {}
    for _ in range(_MAX_META_LINES):
        line = f.readline(_MAX_META_CHARS)
        if not line.startswith("#"):
            return meta, line
        key, sep, value = line[1:].rstrip("\r\n").partition(":")
        if sep:
            meta[key.strip().lower()] = value.strip()
    return meta, f.readline(_MAX_META_CHARS)


def _csv_cells(rows: Iterator[list[str]], width: int, path: Path) -> tuple[list[int], np.ndarray]:
    """Frame numbers and [R, width] float32 cells (empty = NaN) of the data rows; InputError naming a bad row.

    Rows are converted in chunks: each is checked in float64 (finite or NaN, within float32 range) and
    kept as float32.
    """
    numbers: list[int] = []
    chunks: list[np.ndarray] = []
    seen: set[int] = set()
    r = 1  # the header is row 1
    while True:
        block = list(itertools.islice(rows, _CSV_CHUNK))
        if not block:
            break
        values = []
        for row in block:
            r += 1
            if len(row) != width:
                raise InputError(f"{path}: row {r} has {len(row)} cells, the header has {width}")
            try:
                number = int(row[0])
                values.append([float(c) if c.strip() else math.nan for c in row])
            except ValueError:
                raise InputError(f"{path}: row {r} has a non-numeric cell") from None
            if number < 0 or number in seen:
                raise InputError(f"{path}: row {r}: frame {number} is negative or repeated")
            seen.add(number)
            numbers.append(number)
        chunk = np.array(values, dtype=np.float64)  # [N, width]
        with np.errstate(invalid="ignore"):
            bad = np.flatnonzero((np.abs(chunk) > FLOAT32_MAX).any(axis=1))  # inf included, NaN not
        if len(bad):
            raise InputError(f"{path}: row {r - len(block) + 1 + int(bad[0])} has an infinite value or one "
                             "beyond float32 range")
        chunks.append(chunk.astype(np.float32))
    return numbers, np.concatenate(chunks)


def _meta_float(text: str, what: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise InputError(f"{what} must be a positive number, got {text[:40]!r}") from None


def _csv_layout(columns: list[str], declared: str | None, path: Path) -> str:
    """The layout whose joints the ``<joint>_x/_y[/_c]`` columns name."""
    names = []
    for c in columns:
        stem, _, axis = c.rpartition("_")
        if axis not in ("x", "y", "c") or not stem:
            raise InputError(f"{path}: column {c[:40]!r} is not <joint>_x, <joint>_y or <joint>_c")
        names.append(stem)
    joints = set(names)
    candidates = [declared] if declared else list(LAYOUTS)
    for name in candidates:
        if name not in LAYOUTS:
            raise InputError(f"{path}: unknown layout {name[:40]!r}; valid: {', '.join(sorted(LAYOUTS))}")
        lay = LAYOUTS[name]
        if joints == set(lay.joints) and all(f"{j}_x" in columns and f"{j}_y" in columns for j in lay.joints):
            if len(columns) != len(set(columns)):
                raise InputError(f"{path}: repeated column")
            return name
    raise InputError(f"{path}: columns do not name the joints of {declared[:40] if declared else 'any known layout'}")
