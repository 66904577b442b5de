"""Cutting network inputs into windows and putting the outputs back together, for any number of tracks.

Numpy only: the torch and the numpy inference paths (:mod:`retarget.api`) share it, whatever runs the network.
A track of ``T`` frames is reflect-padded to a multiple of the network's downsampling; up to ``window`` frames
it is one pass, longer ones are overlapping windows of ``window`` frames whose outputs are cross-faded
linearly over ``overlap`` frames. Windows of the same length, from one track or from many, go through the
network together, ``frames_per_call`` frames at a time, so memory is bounded by that and not by the tracks.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np


def pad_to_multiple(x: np.ndarray, multiple: int, axis: int = -1) -> tuple[np.ndarray, int]:
    """Reflect-pad the time axis ``axis`` (default the last: ``[..., T]``) on both ends to a multiple of
    ``multiple``; returns (padded, left pad).

    The same frames as ``F.pad(x, (left, right), mode="reflect")``.
    """
    extra = -x.shape[axis] % multiple
    left = extra // 2
    if extra == 0:
        return x, 0
    pads = [(0, 0)] * x.ndim
    pads[axis] = (left, extra - left)
    return np.pad(x, pads, mode="reflect"), left


def strided_starts(frames: int, window: int, stride: int) -> list[int]:
    """Starts every ``stride`` frames, plus one ending at the clip's end when the stride misses it (none when the
    clip is shorter than ``window``): the training windows of a clip, and the windows a static code is averaged
    over."""
    starts = list(range(0, frames - window + 1, stride))
    if starts and starts[-1] != frames - window:
        starts.append(frames - window)
    return starts


def sub_windows(x, length: int, stride: int, concat: Callable) -> tuple[object, int]:
    """The sub-windows a static code of each window of ``x`` [B, C, T] is averaged over: those of ``length`` frames
    ``stride`` apart (:func:`strided_starts`), stacked start-major as [N * B, C, length], and N; ``x`` itself and 1
    when it is no longer than ``length``. ``x`` is a numpy array or a torch tensor; ``concat`` joins a list of them
    along the first axis (``np.concatenate``, ``torch.cat``)."""
    frames = x.shape[-1]
    if frames <= length:
        return x, 1
    starts = strided_starts(frames, length, stride)
    return concat([x[:, :, s : s + length] for s in starts]), len(starts)


def window_starts(total: int, window: int, overlap: int) -> list[int]:
    """First frames of the windows covering ``total`` (> ``window``) frames; the last one ends at ``total``."""
    return list(range(0, total - window, window - overlap)) + [total - window]


def fade_weights(window: int, overlap: int, first: bool, last: bool) -> np.ndarray:
    """[window] float32 weights of one window's output: linear ramps over ``overlap`` frames at the ends that
    another window shares (none before the first window or after the last)."""
    weights = np.ones(window, dtype=np.float32)
    if overlap:
        edge = ((np.arange(overlap, dtype=np.float32) + 0.5) / overlap).astype(np.float32)
        if not first:
            weights[:overlap] = edge
        if not last:
            weights[-overlap:] = edge[::-1]
    return weights


@dataclass(frozen=True)
class _Piece:
    track: int  # index into the inputs
    start: int  # first frame in the padded track
    length: int  # frames


def run_windowed(
    inputs: Sequence[np.ndarray],
    run: Callable[[np.ndarray], np.ndarray],
    multiple: int,
    window: int,
    overlap: int,
    frames_per_call: int,
) -> list[np.ndarray]:
    """Every input through ``run`` in windows, batched across inputs.

    Windows are cut and outputs summed time-major (``[T, C]`` memory, what :mod:`retarget.network.numpy_net` works
    in): ``run`` gets ``[N, C, L]`` views of ``[N, L, C]`` arrays, and the outputs are ``[C', T]`` views of
    ``[T, C']`` ones when the network gives them so. The numbers do not depend on the memory order.

    Args:
        inputs: [C, T_i] float32 arrays (T_i >= the network's shortest input).
        run: the network, [N, C, L] -> [N, C', L] float32 (L a multiple of ``multiple``).
        multiple: the network's downsampling factor.
        window: longest single pass (a multiple of ``multiple``).
        overlap: frames neighbouring windows share (< ``window``).
        frames_per_call: frames per call of ``run`` (at least one window goes).

    Returns:
        [C', T_i] float32 outputs, in the order of ``inputs``.
    """
    padded, lefts, pieces = [], [], defaultdict(list)
    for i, x in enumerate(inputs):
        p, left = pad_to_multiple(x.T, multiple, axis=0)  # [T8, C]
        padded.append(p)
        lefts.append(left)
        total = p.shape[0]
        if total <= window:
            pieces[total].append(_Piece(i, 0, total))
        else:
            pieces[window].extend(_Piece(i, s, window) for s in window_starts(total, window, overlap))
    sums: list[np.ndarray | None] = [None] * len(inputs)  # [T8, C'] weighted sums of window outputs
    weights: list[np.ndarray | None] = [None] * len(inputs)  # [T8]
    out: list[np.ndarray | None] = [None] * len(inputs)
    for length, group in pieces.items():
        step = max(1, frames_per_call // length)
        for k in range(0, len(group), step):
            chunk = group[k : k + step]
            windows = np.stack([padded[p.track][p.start : p.start + length] for p in chunk])  # [N, L, C]
            y = run(windows.transpose(0, 2, 1))  # [N, C', L]
            for piece, yi in zip(chunk, y):
                i, total = piece.track, padded[piece.track].shape[0]
                if total <= window:  # the whole track in one pass
                    out[i] = yi[:, lefts[i] : lefts[i] + inputs[i].shape[-1]]
                    continue
                if sums[i] is None:
                    sums[i] = np.zeros((total, y.shape[1]), dtype=np.float32)
                    weights[i] = np.zeros(total, dtype=np.float32)
                w = fade_weights(window, overlap, piece.start == 0, piece.start == total - window)
                sums[i][piece.start : piece.start + length] += yi.T * w[:, None]
                weights[i][piece.start : piece.start + length] += w
                if piece.start == total - window:  # its last window (a track's windows run in order)
                    sums[i] /= weights[i][:, None]  # in place: the same quotients, no second track-sized array
                    out[i] = sums[i][lefts[i] : lefts[i] + inputs[i].shape[-1]].T
                    sums[i] = weights[i] = None  # free it now: memory stays bounded by the tracks in flight
    return out  # type: ignore[return-value]
