"""The fast numpy paths of retargeting's preparation give the numbers of the plain formulas, bit for bit.

Each reference below is the formulation the code had before it was made faster (time-major arrays, fancy
indexing, broadcasting along the 2-long coordinate axis, channel-major windows; the smoothing filter in
blocks: tests/pose_io/test_clean_smooth_parity.py); the new code must agree with them exactly, not just closely.
"""

from __future__ import annotations

from collections import defaultdict

import numpy as np
import pytest

from retarget.inference.placement import Placement, _stand, place
from retarget.inference.windows import fade_weights, run_windowed, window_starts
from retarget.network.preprocess import (
    LAYOUT,
    LOCAL_INDEX,
    NUM_CHANNELS,
    NUM_ROWS,
    ROOT_INDEX,
    NormStats,
    channels_to_joints,
    joints_to_channels,
    row_statistics,
)


def _stats(rng: np.random.Generator) -> NormStats:
    return NormStats(rng.normal(0, 20, (NUM_ROWS, 2)), rng.uniform(0.5, 40, (NUM_ROWS, 2)))


def _joints(rng: np.random.Generator, shape: tuple[int, ...], dtype=np.float64) -> np.ndarray:
    return rng.normal(256, 80, (*shape, len(LAYOUT), 2)).astype(dtype)


def _reference_to_channels(joints: np.ndarray, stats: NormStats) -> np.ndarray:
    b, t = joints.shape[:2]
    root = joints[:, :, ROOT_INDEX]
    local = joints[:, :, list(LOCAL_INDEX)] - root[:, :, None]
    velocity = np.zeros_like(root)
    velocity[:, 1:] = root[:, 1:] - root[:, :-1]
    x = np.concatenate([local, velocity[:, :, None]], axis=2).reshape(b, t, NUM_CHANNELS).swapaxes(1, 2)
    mean = stats.mean.reshape(1, NUM_CHANNELS, 1).astype(x.dtype)
    std = stats.std.reshape(1, NUM_CHANNELS, 1).astype(x.dtype)
    return (x - mean) / std


def _reference_to_joints(x: np.ndarray, stats: NormStats, start=None) -> np.ndarray:
    b, _, t = x.shape
    shape = (1, 1, NUM_CHANNELS)
    mean, std = (a.reshape(shape).astype(x.dtype) for a in (stats.mean, stats.std))
    rows = (np.ascontiguousarray(x.swapaxes(1, 2)) * std + mean).reshape(b, t, NUM_ROWS, 2)
    root = np.cumsum(rows[:, :, -1], axis=1)
    if start is not None:
        root = root + np.asarray(start, dtype=x.dtype).reshape(-1, 1, 2)
    joints = np.empty((b, t, len(LAYOUT), 2), dtype=x.dtype)
    joints[:, :, list(LOCAL_INDEX)] = rows[:, :, :-1] + root[:, :, None]
    joints[:, :, ROOT_INDEX] = 0.0 + root
    return joints


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    return a.dtype == b.dtype and a.shape == b.shape and np.ascontiguousarray(a).tobytes() == np.ascontiguousarray(
        b).tobytes()  # fmt: skip


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("frames", [1, 2, 9, 120, 1001])
def test_channels_both_ways_are_the_plain_formulas(dtype, frames):
    rng = np.random.default_rng(frames)
    stats = _stats(rng)
    joints = _joints(rng, (3, frames), dtype)
    assert _same(joints_to_channels(joints, stats), _reference_to_channels(joints, stats))
    mine = joints.copy()  # in its memory when it can
    assert _same(joints_to_channels(mine, stats, overwrite=True), _reference_to_channels(joints, stats))
    strided = np.asfortranarray(joints)  # it cannot: computed as without overwrite, the input untouched
    assert _same(joints_to_channels(strided, stats, overwrite=True), _reference_to_channels(joints, stats))
    assert _same(strided, joints)
    x = rng.normal(0, 1, (3, NUM_CHANNELS, frames)).astype(dtype)
    time_major = np.ascontiguousarray(x.swapaxes(1, 2)).swapaxes(1, 2)  # the same values, the network's order
    start = rng.normal(0, 100, (3, 2))
    for inp in (x, time_major):
        assert _same(channels_to_joints(inp, stats), _reference_to_joints(inp, stats))
        assert _same(channels_to_joints(inp, stats, start), _reference_to_joints(inp, stats, start))
        for with_start in (None, start):  # in the input's memory where it can be (time-major), else not
            expected = _reference_to_joints(inp, stats, with_start)
            assert _same(channels_to_joints(inp.copy(order="K"), stats, with_start, overwrite=True), expected)


def test_row_statistics_are_unchanged():
    rng = np.random.default_rng(1)
    windows = _joints(rng, (4, 64))
    rows = _reference_to_channels(windows, NormStats(np.zeros((NUM_ROWS, 2)), np.ones((NUM_ROWS, 2))))
    flat = rows.swapaxes(1, 2).reshape(-1, NUM_ROWS, 2)
    stats = row_statistics(windows, min_std=1.0)
    assert _same(stats.mean, flat.mean(axis=0)) and _same(stats.std, np.maximum(flat.std(axis=0), 1.0))


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_place_is_joints_plus_the_shift(dtype):
    rng = np.random.default_rng(2)
    joints = _joints(rng, (200,), dtype)
    target = Placement(300.0, 123.25, 456.5)
    root_x, ground_y = _stand(joints)
    expected = joints + np.array([target.root_x - root_x, target.ground_y - ground_y])
    assert _same(place(joints, target), expected)


def _reference_windowed(inputs, run, multiple, window, overlap, frames_per_call):
    """run_windowed as it was: channel-major windows and sums."""
    padded, lefts, pieces = [], [], defaultdict(list)
    for i, x in enumerate(inputs):
        extra = -x.shape[-1] % multiple
        left = extra // 2
        p = np.pad(x, [(0, 0), (left, extra - left)], mode="reflect") if extra else x
        padded.append(p)
        lefts.append(left)
        total = p.shape[-1]
        if total <= window:
            pieces[total].append((i, 0, total))
        else:
            pieces[window].extend((i, s, window) for s in window_starts(total, window, overlap))
    sums, weights, out = [None] * len(inputs), [None] * len(inputs), [None] * len(inputs)
    for length, group in pieces.items():
        step = max(1, frames_per_call // length)
        for k in range(0, len(group), step):
            chunk = group[k : k + step]
            y = run(np.stack([padded[i][:, s : s + length] for i, s, _ in chunk]))
            for (i, s, _), yi in zip(chunk, y):
                total = padded[i].shape[-1]
                if total <= window:
                    out[i] = yi[:, lefts[i] : lefts[i] + inputs[i].shape[-1]]
                    continue
                if sums[i] is None:
                    sums[i] = np.zeros((y.shape[1], total), dtype=np.float32)
                    weights[i] = np.zeros(total, dtype=np.float32)
                w = fade_weights(window, overlap, s == 0, s == total - window)
                sums[i][:, s : s + length] += yi * w
                weights[i][s : s + length] += w
                if s == total - window:
                    out[i] = (sums[i] / weights[i])[:, lefts[i] : lefts[i] + inputs[i].shape[-1]]
    return out


def test_time_major_windows_give_the_channel_major_results():
    rng = np.random.default_rng(3)
    inputs = [rng.normal(size=(NUM_CHANNELS, n)).astype(np.float32) for n in (16, 21, 120, 300, 1001, 37, 700)]
    mixing = rng.normal(size=(NUM_CHANNELS, NUM_CHANNELS)).astype(np.float32)

    def network(windows: np.ndarray) -> np.ndarray:  # [N, C, L] -> [N, C, L]: mixes channels and time
        w = np.ascontiguousarray(windows)
        return (np.einsum("dc,ncl->ndl", mixing, w) + 0.5 * np.roll(w, 3, axis=-1)).astype(np.float32)

    def time_major(windows: np.ndarray) -> np.ndarray:  # the same numbers as [N, C, L] views of [N, L, C]
        return np.ascontiguousarray(network(windows).swapaxes(1, 2)).swapaxes(1, 2)

    expected = _reference_windowed(inputs, network, 8, 128, 32, 256)
    for run in (network, time_major):
        for g, e in zip(run_windowed(inputs, run, 8, 128, 32, 256), expected):
            assert _same(g, e)


def test_channels_of_strided_and_integer_joints_take_the_plain_path_alike():
    rng = np.random.default_rng(4)
    stats = _stats(rng)
    joints = _joints(rng, (2, 50))
    strided = np.asfortranarray(joints)  # last axis not contiguous: no complex view
    assert _same(joints_to_channels(strided, stats), _reference_to_channels(strided, stats))
    integers = joints.astype(np.int64)
    assert _same(joints_to_channels(integers, stats), _reference_to_channels(integers, stats))
    target = Placement(300.0, 12.5, 40.25)
    root_x, ground_y = _stand(strided[0])
    shift = np.array([target.root_x - root_x, target.ground_y - ground_y])
    assert _same(place(strided[0], target), strided[0] + shift)


def test_finished_tracks_are_the_plain_formula_and_share_no_memory():
    """retarget_many's tracks (their joints written where the network output of each lay) are the plain
    formula of the output, bit for bit, each in memory of its own; long tracks cross several windows."""
    from pose_io.clean import smooth_joints as smooth
    from retarget.api import InferenceConfig, load_retargeter
    from tests.figures import tall_and_small, walking_figure

    retargeter = load_retargeter(config=InferenceConfig(window=128, overlap=32, batch=2), backend="numpy")
    reference = retargeter.reference_codes(tall_and_small(96)["small"])
    drivers = [walking_figure(n, seed=n) for n in (40, 96, 96, 300, 17)]
    outputs = []
    original = retargeter._finish
    retargeter._finish = lambda y, *args: outputs.append(y.copy()) or original(y, *args)  # type: ignore[method-assign]
    many = retargeter.retarget_many(drivers, reference)
    scale = retargeter._reference_scale(reference)
    for y, moved in zip(outputs, many):
        canvas = _reference_to_joints(y[None].astype(np.float64), retargeter.stats)[0]
        expected = place(smooth(canvas / scale, retargeter.preprocess.output_sigma), reference.placement)
        assert _same(moved.joints, expected.astype(np.float32))
    for i, a in enumerate(many):
        assert not any(np.shares_memory(a.joints, b.joints) for b in many[i + 1 :])


@pytest.mark.parametrize("frames", [1, 9, 1001])
def test_channels_in_another_type_are_the_plain_formulas_converted(frames):
    """joints_to_channels(..., dtype=float32) is the float64 result rounded once; channels_to_joints(x32,
    dtype=float64) the float64 formula of the converted x: no converted copy made, the same numbers."""
    rng = np.random.default_rng(frames + 10)
    stats = _stats(rng)
    joints = _joints(rng, (2, frames))
    expected = _reference_to_channels(joints, stats).astype(np.float32)
    for overwrite in (False, True):
        got = joints_to_channels(joints.copy(), stats, overwrite=overwrite, dtype=np.float32)
        assert _same(got, expected) and got.swapaxes(1, 2).flags.c_contiguous  # time-major, as the network works
    x = rng.normal(0, 1, (2, NUM_CHANNELS, frames)).astype(np.float32)
    start = rng.normal(0, 100, (2, 2))
    for inp in (x, np.ascontiguousarray(x.swapaxes(1, 2)).swapaxes(1, 2)):
        for with_start in (None, start):
            expected = _reference_to_joints(inp.astype(np.float64), stats, with_start)
            assert _same(channels_to_joints(inp, stats, with_start, dtype=np.float64), expected)
            mine = inp.copy(order="K")  # not of the result's type: never its memory, left as it was
            assert _same(channels_to_joints(mine, stats, with_start, overwrite=True, dtype=np.float64), expected)
            assert _same(mine, inp)


def test_channel_types_are_for_arrays():
    torch = pytest.importorskip("torch")
    stats = _stats(np.random.default_rng(5))
    with pytest.raises(TypeError, match="numpy arrays"):
        joints_to_channels(torch.zeros(1, 4, len(LAYOUT), 2), stats, dtype=np.float32)
    with pytest.raises(TypeError, match="numpy arrays"):
        channels_to_joints(torch.zeros(1, NUM_CHANNELS, 4), stats, dtype=np.float64)


def test_a_body15_track_is_prepared_from_its_own_joints():
    """No converted copy of a track already in body15: its own (read-only) joints, the numbers of its body25
    original's conversion."""
    from retarget.inference.tracks import _body15_joints, prepare
    from retarget.network.preprocess import PreprocessConfig
    from tests.figures import walking_figure

    body25 = walking_figure(80, dropped=0.1, always_seen=("mid_hip", "l_ankle", "r_ankle"), seed=3)
    body15 = body25.to_layout(LAYOUT.name)
    assert _body15_joints(body15, "t") is body15.joints and not body15.joints.flags.writeable
    for config in (PreprocessConfig(), PreprocessConfig(body_height=150.0)):
        a, b = prepare(body25, config), prepare(body15, config)
        assert _same(a.canvas, b.canvas) and a.scale == b.scale and _same(a.body15, b.body15)
