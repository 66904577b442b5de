"""Fuzzing the .npz, .npy and .csv readers: every generated file gives a sane track or an InputError.

Files start from valid tracks and are then damaged: hostile values (1e6, 1e30, 1e39, 1e308, inf, NaN,
negative), wrong dtypes (complex, text, bool, half), wrong shapes, hostile fps / image sizes / layouts,
truncated or corrupted bytes. A track that comes back must obey the limits of :mod:`pose_io.limits`.
"""

from __future__ import annotations

import io
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import event, given
from hypothesis import strategies as st

from pose_io import InputError, PoseTrack, read_track, write_track
from pose_io.layouts import LAYOUTS
from pose_io.limits import MAX_FPS, MAX_IMAGE_SIDE, MIN_FPS, TRACK_RANGE
from tests.pose_io.fuzzing import HOSTILE_NUMBERS, fast_and_slow, mutated_text

_COORDS = [1e6, -1e6, 1e30, -1e30, 1e39, 1e308, np.inf, -np.inf, np.nan, -5.0, 700.0, 2e4, 1e5]
_DTYPES = ["<f2", "<f4", "<f8", "<i4", "<i8", "|u1", "<c16", "|b1", "<U3"]
_FPS = [30.0, 0.0, -1.0, 1e9, np.nan, np.inf, 1e-9, 1000.0, 1000.5, "30", [30.0, 31.0], 30j, True, 2**70]
_SIZES = [[640, 480], [0, 480], [100000, 100000], [np.inf, 5.0], [np.nan, 4.0], [640], [[640, 480]], "640x480",
          [640.5, 480], [-1, 2], [2**62, 2], [1e30, 5.0], [16384, 16384], [16385, 2], [640j, 480]]
_LAYOUTS = ["body25", "coco18", "body15", "nope", "", "x" * 500, 5, ["body25"], b"body25"]


def assert_sane(track: PoseTrack) -> None:
    """What every track that comes out of a reader must satisfy."""
    w, h = track.image_size
    assert 1 <= w <= MAX_IMAGE_SIDE and 1 <= h <= MAX_IMAGE_SIDE
    assert MIN_FPS <= track.fps <= MAX_FPS
    assert track.joints.dtype == np.float32 and not np.isinf(track.joints).any()
    visible = ~track.missing
    reach = TRACK_RANGE * max(w, h)
    assert (track.joints[visible] >= -reach).all() and (track.joints[visible] <= max(w, h) + reach).all()
    assert np.isnan(track.joints).any(axis=-1).sum() == (track.confidence == 0).sum()


def _cast(values: np.ndarray, dtype: str) -> np.ndarray:
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return np.asarray(values).astype(dtype)


@st.composite
def npz_bytes(draw: st.DrawFn) -> bytes:
    """An .npz archive made from a random track and then damaged."""
    n = draw(st.sampled_from([15, 17, 18, 25, 33, 20]))
    t = draw(st.integers(1, 5))
    rng = np.random.default_rng(draw(st.integers(0, 2**16)))
    joints = rng.uniform(0, 600, (t, n, 2))
    conf = rng.uniform(0, 1, (t, n))
    entries: dict[str, object] = {"joints": joints, "confidence": conf}
    if draw(st.booleans()):
        entries.update(fps=30.0, image_size=np.array([640, 480]),
                       layout=next((k for k, v in LAYOUTS.items() if len(v) == n), "body25"))
    for _ in range(draw(st.integers(0, 3))):
        kind = draw(st.sampled_from(["coord", "coord", "conf", "dtype", "shape", "drop", "fps", "size", "layout"]))
        key = {"coord": "joints", "conf": "confidence", "dtype": draw(st.sampled_from(["joints", "confidence"])),
               "shape": draw(st.sampled_from(["joints", "confidence"]))}.get(kind)
        arr = np.asarray(entries.get(key, []))
        if key is not None and (key not in entries or arr.dtype.kind not in "iuf" or not arr.size):
            continue  # dropped or made text earlier: nothing to edit
        if kind in ("coord", "conf"):
            arr = arr.astype(np.float64)  # a copy
            pool = _COORDS if kind == "coord" else [0.0, 1.0, 1.5, -0.1, np.nan]
            arr.flat[draw(st.integers(0, arr.size - 1))] = draw(st.sampled_from(pool))
            entries[key] = arr
        elif kind == "dtype":
            entries[key] = _cast(arr, draw(st.sampled_from(_DTYPES)))
        elif kind == "shape":
            entries[key] = draw(st.sampled_from([arr[:0], arr[..., :1], arr.reshape(-1), arr[None], arr.T]))
        elif kind == "drop":
            if entries:
                entries.pop(draw(st.sampled_from(sorted(entries))))
        else:
            pool = {"fps": _FPS, "size": _SIZES, "layout": _LAYOUTS}[kind]
            entries["image_size" if kind == "size" else kind] = draw(st.sampled_from(pool))
    buf = io.BytesIO()
    arrays = {k: np.asarray(v) for k, v in entries.items()}
    np.savez(buf, **arrays)
    raw = buf.getvalue()
    damage = draw(st.sampled_from(["none", "none", "none", "cut", "flip"]))
    if damage == "cut":
        raw = raw[: draw(st.integers(0, len(raw)))]
    elif damage == "flip" and raw:
        i = draw(st.integers(0, len(raw) - 1))
        raw = raw[:i] + bytes([raw[i] ^ draw(st.integers(1, 255))]) + raw[i + 1:]
    return raw


def _read_case(tmp_path_factory: pytest.TempPathFactory, raw: bytes, suffix: str) -> None:
    path = tmp_path_factory.mktemp("fuzz") / f"poses{suffix}"
    path.write_bytes(raw)
    try:
        track = read_track(path)
    except InputError as exc:
        assert "\n" not in str(exc)
        event("InputError")
        return
    event("track")
    assert_sane(track)


test_npz_reader_fuzz, test_npz_reader_fuzz_slow = fast_and_slow(
    lambda: given(raw=npz_bytes(), suffix=st.just(".npz"))(_read_case), fast=120)


@st.composite
def npy_bytes(draw: st.DrawFn) -> bytes:
    """A .npy array [T, J, 2|3] with hostile values, dtypes or shapes, sometimes cut short."""
    shape = draw(st.sampled_from([(3, 25, 3), (2, 15, 2), (1, 33, 3), (3, 25), (0, 25, 2), (2, 20, 2)]))
    arr = np.random.default_rng(draw(st.integers(0, 99))).uniform(0, 1, shape) * 300
    if len(shape) == 3 and shape[2] == 3:
        arr[..., 2] /= 300
    if arr.size and draw(st.booleans()):
        arr.flat[draw(st.integers(0, arr.size - 1))] = draw(st.sampled_from(_COORDS))
    arr = _cast(arr, draw(st.sampled_from(["<f8", "<f8", "<f4", "<c16", "<U3", "|b1"])))
    buf = io.BytesIO()
    np.save(buf, arr)
    raw = buf.getvalue()
    return raw[: draw(st.integers(0, len(raw)))] if draw(st.integers(0, 4)) == 0 else raw


test_npy_reader_fuzz, test_npy_reader_fuzz_slow = fast_and_slow(
    lambda: given(raw=npy_bytes(), suffix=st.just(".npy"))(_read_case), fast=40)


def _csv_text(layout: str, frames: int, seed: int) -> str:
    rng = np.random.default_rng(seed)
    n = len(LAYOUTS[layout])
    joints = rng.uniform(0, 600, (frames, n, 2)).astype(np.float32)
    conf = rng.uniform(0.1, 1, (frames, n)).astype(np.float32)
    conf[0, 0] = 0.0  # one missing joint: empty cells
    track = PoseTrack(joints, conf, 25.0, (640, 480), layout)
    with tempfile.TemporaryDirectory() as tmp:
        return write_track(track, Path(tmp) / "a.csv").read_text()


_CSV_BASES = [_csv_text("body15", 3, 0), _csv_text("coco17", 2, 1), _csv_text("body25", 1, 2)]
_META = ["# fps: {}", "# image_size: {}x{}", "# layout: {}", "# image_size: {}", "#{}"]


@st.composite
def csv_texts(draw: st.DrawFn) -> str:
    """Our CSV with cells replaced by hostile tokens, rows dropped or repeated, meta lines changed, cut short."""
    text = draw(mutated_text(draw(st.sampled_from(_CSV_BASES)), sep=",", max_edits=5))
    for _ in range(draw(st.integers(0, 2))):
        line = draw(st.sampled_from(_META))
        tokens = [draw(st.sampled_from(HOSTILE_NUMBERS + ["body25", "coco17", "x"])) for _ in range(line.count("{}"))]
        text = line.format(*tokens) + "\n" + text
    return text


test_csv_reader_fuzz, test_csv_reader_fuzz_slow = fast_and_slow(
    lambda: given(raw=csv_texts().map(lambda t: t.encode("utf-8", "surrogatepass")), suffix=st.just(".csv"))(
        _read_case), fast=120)
