"""retarget.inference.windows: padding, windows and cross-fades put every frame back where it came from."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import torch
import torch.nn.functional as F

from retarget.inference.windows import fade_weights, pad_to_multiple, run_windowed, window_starts


@pytest.mark.parametrize("length", [8, 9, 13, 16, 23])
def test_padding_is_torchs_reflection(length):
    x = np.random.default_rng(length).normal(size=(2, 30, length)).astype(np.float32)
    padded, left = pad_to_multiple(x, 8)
    extra = -length % 8
    expected = F.pad(torch.from_numpy(x), (extra // 2, extra - extra // 2), mode="reflect").numpy()
    np.testing.assert_array_equal(padded, expected)
    assert left == extra // 2 and padded.shape[-1] % 8 == 0


def test_windows_cover_the_track_and_fades_sum_to_one_inside():
    starts = window_starts(1000, 256, 64)
    assert starts[0] == 0 and starts[-1] == 1000 - 256 and all(b - a == 192 for a, b in itertools.pairwise(starts[:-1]))
    total = np.zeros(1000, np.float32)
    for s in starts:
        total[s : s + 256] += fade_weights(256, 64, s == 0, s == starts[-1])
    assert total.min() >= 1.0 - 1e-6 and np.allclose(total[: starts[-1]], 1.0)  # the last window overlaps more


def test_a_pointwise_network_gives_back_its_input_for_any_lengths_and_batching():
    rng = np.random.default_rng(0)
    inputs = [rng.normal(size=(30, n)).astype(np.float32) for n in (16, 21, 120, 120, 300, 1001, 37)]
    calls = []

    def run(windows: np.ndarray) -> np.ndarray:
        calls.append(windows.shape)
        return 2.0 * windows  # [N, 30, L]

    out = run_windowed(inputs, run, multiple=8, window=128, overlap=32, frames_per_call=256)
    assert [o.shape for o in out] == [x.shape for x in inputs]
    for x, y in zip(inputs, out):
        np.testing.assert_allclose(y, 2.0 * x, rtol=1e-6, atol=1e-6)
    assert all(n * length <= 256 or n == 1 for n, _, length in calls)  # frames per call bounded
    assert any(n > 1 for n, _, length in calls if length == 120)  # clips of one length stacked together


def test_windows_of_one_track_are_cross_faded():
    x = np.zeros((1, 300), np.float32)
    count = []

    def run(windows: np.ndarray) -> np.ndarray:  # every window outputs its number: the output shows the fades
        count.append(1)
        return np.full_like(windows, len(count) - 1)

    y = run_windowed([x], run, multiple=8, window=128, overlap=32, frames_per_call=128)[0][0]
    assert y[0] == 0 and y[-1] == 2 and np.all(np.diff(y) >= 0)  # 0 -> 1 -> 2, monotone ramps between
