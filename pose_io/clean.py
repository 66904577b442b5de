"""Opt-in cleaning of pose tracks: filling short gaps, smoothing, dropping outlier joints (changing fps:
:mod:`pose_io.resample`).

Nothing here runs unless asked for; every function returns a new track and leaves missing data
explicit where it cannot honestly be made up.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from pose_io.errors import InputError
from pose_io.limits import Dropped, outlier_mask
from pose_io.track import PoseTrack

log = logging.getLogger(__name__)

#: Frames :func:`smooth_joints` works out at once (a block of body15 frames and its temporaries stay in the cache).
_SMOOTH_BLOCK = 1024


@dataclass(frozen=True)
class Gap:
    """A run of frames ``start:stop`` in which joint ``joint`` is missing.

    ``reason`` is ``"filled"``, ``"too long"`` (longer than ``max_gap``) or ``"edge"`` (touches the start
    or end of the track, so there is nothing to interpolate towards).
    """

    joint: str
    start: int
    stop: int
    reason: str

    @property
    def length(self) -> int:
        return self.stop - self.start


@dataclass(frozen=True)
class GapReport:
    """What :func:`fill_gaps` did: the gaps it filled and the ones left missing."""

    filled: tuple[Gap, ...]
    unfilled: tuple[Gap, ...]

    @property
    def frames_filled(self) -> int:
        return sum(g.length for g in self.filled)

    def summary(self) -> str:
        """One line for people: counts, then the unfilled gaps as ``joint frames a-b``."""
        text = f"filled {len(self.filled)} gaps ({self.frames_filled} joint-frames)"
        if self.unfilled:
            shown = ", ".join(f"{g.joint} frames {g.start}-{g.stop - 1} ({g.reason})" for g in self.unfilled[:8])
            more = f", and {len(self.unfilled) - 8} more" if len(self.unfilled) > 8 else ""
            text += f"; left missing: {shown}{more}"
        return text


def true_runs(missing: np.ndarray) -> list[tuple[int, int]]:
    """(start, stop) of each run of True in a [T] bool array."""
    padded = np.concatenate([[False], missing, [False]]).astype(np.int8)
    edges = np.flatnonzero(np.diff(padded))
    return list(zip(edges[::2].tolist(), edges[1::2].tolist()))


def fill_gaps(track: PoseTrack, max_gap: int) -> tuple[PoseTrack, GapReport]:
    """Fill gaps of at most ``max_gap`` frames per joint by linear interpolation.

    Coordinates and confidence are interpolated between the last frame before and the first frame
    after the gap. Longer gaps, and gaps at the start or end of the track, stay missing and are
    reported.

    Args:
        track: the track.
        max_gap: longest run of missing frames to fill (0 fills nothing).

    Returns:
        The new track and a :class:`GapReport`.
    """
    if max_gap < 0:
        raise InputError(f"max_gap must be >= 0, got {max_gap}")
    joints = track.joints.copy()  # [T, J, 2]
    conf = track.confidence.copy()  # [T, J]
    t_len = track.num_frames
    names = track.joint_layout.joints
    filled: list[Gap] = []
    unfilled: list[Gap] = []
    for j, name in enumerate(names):
        for start, stop in true_runs(track.missing[:, j]):
            if start == 0 or stop == t_len:
                unfilled.append(Gap(name, start, stop, "edge"))
                continue
            if stop - start > max_gap:
                unfilled.append(Gap(name, start, stop, "too long"))
                continue
            a, b = start - 1, stop
            w = ((np.arange(start, stop) - a) / (b - a))[:, None]  # [G, 1]
            joints[start:stop, j] = (1 - w) * joints[a, j] + w * joints[b, j]
            conf[start:stop, j] = (1 - w[:, 0]) * conf[a, j] + w[:, 0] * conf[b, j]
            filled.append(Gap(name, start, stop, "filled"))
    order = {n: i for i, n in enumerate(names)}
    unfilled.sort(key=lambda g: (g.start, order[g.joint]))
    report = GapReport(tuple(filled), tuple(unfilled))
    if unfilled:
        log.info("fill_gaps: %s", report.summary())
    return track.replace(joints=joints, confidence=conf), report


def drop_outlier_joints(track: PoseTrack) -> tuple[PoseTrack, Dropped]:
    """``track`` with its outlier joints made missing (rules in :mod:`pose_io.limits`), and what was dropped.

    Readers already do this; it is for tracks made in code. Nothing is logged here: callers say it once.

    Returns:
        The track (the same object when nothing was dropped) and a :class:`pose_io.limits.Dropped`.
    """
    outliers = outlier_mask(track.joints, track.image_size)  # [T, J]
    if not outliers.any():
        return track, Dropped(0)
    t, j = (int(v) for v in np.argwhere(outliers)[0])
    x, y = (float(v) for v in track.joints[t, j])
    dropped = Dropped(int(outliers.sum()), t, track.joint_layout.joints[j], x, y)
    joints = np.where(outliers[..., None], np.nan, track.joints)
    return track.replace(joints=joints), dropped


def gaussian_kernel(sigma: float, max_radius: int | None = None) -> np.ndarray:
    """[2r+1] Gaussian weights (not normalised), r = ceil(4 sigma), at most ``max_radius`` when given."""
    radius = max(1, math.ceil(4.0 * sigma))
    if max_radius is not None:
        radius = max(1, min(radius, max_radius))
    k = np.arange(-radius, radius + 1, dtype=np.float64)
    return np.exp(-0.5 * (k / sigma) ** 2)


def smooth(track: PoseTrack, sigma: float) -> PoseTrack:
    """Temporal Gaussian smoothing weighted by confidence; missing joints stay missing.

    Each visible joint becomes ``sum_k g(k) c[t+k] x[t+k] / sum_k g(k) c[t+k]`` over visible neighbours
    (the kernel is cut at the track's ends and renormalised), so a low-confidence detection pulls its
    neighbours little and a missing one not at all. Confidence is unchanged.

    Args:
        track: the track.
        sigma: standard deviation in frames; 0 returns the track unchanged.

    Returns:
        The smoothed track.
    """
    if not (math.isfinite(sigma) and sigma >= 0):
        raise InputError(f"smoothing sigma must be >= 0, got {sigma}")
    if sigma == 0:
        return track
    t_len = track.num_frames
    # Offsets of T frames or more never meet the track, so the kernel stops there whatever sigma says.
    kernel = gaussian_kernel(sigma, max_radius=t_len)
    radius = len(kernel) // 2
    weight = track.confidence.astype(np.float64)  # [T, J], 0 where missing
    xy = np.nan_to_num(track.joints.astype(np.float64)) * weight[..., None]  # [T, J, 2]
    num = np.zeros_like(xy)
    den = np.zeros_like(weight)
    for offset, g in zip(range(-radius, radius + 1), kernel):
        # out[t] += g * in[t + offset] over the frames where t + offset exists.
        lo, hi = max(0, -offset), min(t_len, t_len - offset)
        if lo >= hi:
            continue
        num[lo:hi] += g * xy[lo + offset:hi + offset]
        den[lo:hi] += g * weight[lo + offset:hi + offset]
    missing = track.missing
    out = np.where(missing[..., None], np.nan, num / np.where(den > 0, den, 1.0)[..., None])
    return track.replace(joints=out.astype(np.float32))


def hold_fill(joints: np.ndarray) -> np.ndarray:
    """Fill missing joints from the previous frame, then leading gaps from the next (the authors' rule).

    Args:
        joints: [T, J, 2] with NaN where missing; every joint seen at least once.

    Returns:
        [T, J, 2] without NaN.
    """
    t = joints.shape[0]
    seen = ~np.isnan(joints[..., 0])  # [T, J]
    frame = np.where(seen, np.arange(t)[:, None], -1)
    last = np.maximum.accumulate(frame, axis=0)  # index of the last seen frame, -1 before the first
    first = np.argmax(seen, axis=0)  # [J] first seen frame
    source = np.where(last >= 0, last, first[None, :])  # [T, J]
    return np.take_along_axis(joints, source[..., None], axis=0)


def smooth_joints(joints: np.ndarray, sigma: float, *, out: np.ndarray | None = None,
                  block: int = _SMOOTH_BLOCK) -> np.ndarray:
    """Gaussian filter over time (axis 0) of complete joints, reflecting at the ends (the authors' rule).

    Unlike :func:`smooth` (tracks with gaps, confidence-weighted), every value must be present.
    ``scipy.ndimage.gaussian_filter1d(joints, sigma, axis=0, mode="reflect")`` to the bit (tested), in
    numpy: importing scipy.ndimage costs ~0.3 s, a third of a short `clone retarget apply`. Same kernel
    (radius ``int(4 sigma + 0.5)``, normalised), same half-sample reflection, same float64 sums in scipy's
    order. Worked out ``block`` frames at a time, each read with the frames its kernel reaches on either
    side where they lie (only the track's two ends are copied, reflected): the filter makes 3 passes per
    tap over its input, and a block of body15 frames stays in the cache where a long track's passes go to
    memory.

    Args:
        joints: [T, ...] without NaN.
        sigma: standard deviation in frames (0 = a copy).
        out: [T, ...] array to write the result into (``joints`` itself is allowed: a block is written back
            once the next one, the last to read its frames, has been smoothed); a new one of ``joints``'
            dtype when None.
        block: frames smoothed at once.

    Returns:
        ``out``, or the new [T, ...] array.
    """
    data = np.asarray(joints)
    if out is None:
        out = np.empty(data.shape, dtype=data.dtype)
    elif out.shape != data.shape:
        raise ValueError(f"out has shape {out.shape}, joints {data.shape}")
    if sigma <= 0:
        if out is not data:
            out[...] = data
        return out
    radius = int(4.0 * float(sigma) + 0.5)
    taps = np.arange(-radius, radius + 1)
    weights = np.exp(-0.5 / (sigma * sigma) * taps**2)
    weights = (weights / weights.sum())[::-1]
    t = data.shape[0]
    step = block if radius <= block < t else max(t, 1)  # a kernel wider than a block: the track at once
    buffers = [np.empty((min(step, t), *data.shape[1:])) for _ in range(2 if t > step else 1)]  # float64
    pair = np.empty_like(buffers[0])  # reused: fresh temporaries would cost more than the sums
    pending: tuple[slice, np.ndarray] | None = None  # a smoothed block not written yet
    for i, start in enumerate(range(0, t, step)):
        stop = min(start + step, t)
        n = stop - start
        padded = _reflected(data, start - radius, stop + radius)  # [n + 2 radius, ...] float64
        acc = buffers[i % len(buffers)][:n]
        np.multiply(padded[radius : radius + n], weights[radius], out=acc)
        tmp = pair[:n]
        for j in range(radius, 0, -1):
            np.add(padded[radius - j : radius - j + n], padded[radius + j : radius + j + n], out=tmp)
            tmp *= weights[radius - j]
            acc += tmp
        if pending is not None:
            out[pending[0]] = pending[1]
        pending = (slice(start, stop), acc)
    if pending is not None:
        out[pending[0]] = pending[1]
    return out


def _reflected(data: np.ndarray, lo: int, hi: int) -> np.ndarray:
    """Frames ``lo:hi`` of [T, ...] ``data`` as float64, mirrored at its ends (half-sample, as often as needed:
    scipy's "reflect", np.pad's "symmetric"); a view of ``data`` where it needs no mirror and is float64."""
    t = data.shape[0]
    if 0 <= lo and hi <= t:
        return data[lo:hi].astype(np.float64, copy=False)
    if -t <= lo and hi <= 2 * t:  # at most one mirror image at each end
        parts = [data[: max(-lo, 0)][::-1], data[max(lo, 0) : min(hi, t)], data[::-1][: max(hi - t, 0)]]
        return np.concatenate(parts).astype(np.float64, copy=False)
    frames = np.arange(lo, hi) % (2 * t)  # the mirrored track repeats every 2T frames
    return data.take(np.where(frames < t, frames, 2 * t - 1 - frames), axis=0).astype(np.float64, copy=False)


def interpolate_missing(values: np.ndarray) -> np.ndarray:
    """[T] values with NaNs filled linearly in time (held constant beyond the ends); all-NaN stays NaN."""
    values = np.asarray(values, dtype=np.float64)
    ok = np.isfinite(values)
    if ok.all() or not ok.any():
        return values.copy()
    t = np.arange(len(values))
    return np.interp(t, t[ok], values[ok])
