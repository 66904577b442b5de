"""Network input of the retargeting model, and the pose maths around it.

Conventions of Aberman et al. 2019 (and of their released weights):

* Poses are body15 joints (the first 15 BODY_25 joints) in a canvas ``canvas_height`` (512) pixels high:
  a track is scaled by ``canvas_height / image_height``.
* The network sees ``[B, 30, T]``: 15 rows of (x, y) pairs, channel ``2r`` = x and ``2r + 1`` = y of row
  ``r``. Rows 0-13 are the joints other than MidHip minus MidHip of the same frame, in body15 order; row
  14 is the MidHip velocity ``v[t] = root[t] - root[t - 1]`` with ``v[0] = 0``. Every row is normalised
  with per-row mean/std statistics (:class:`NormStats`). Channels 0-27 (the pose) feed the skeleton and
  view encoders; channels 28-29 (the velocity) only the motion encoder.

:func:`joints_to_channels` builds that tensor and :func:`channels_to_joints` undoes it; everything else
reaches channel groups through :func:`pose_channels` and :func:`velocity_channels`. These take numpy arrays
or torch tensors alike and return the same kind, so the torch-free inference path (:mod:`retarget.network.numpy_net`)
shares them: this module does not import torch unless it is handed a tensor.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from pose_io.errors import InputError
from pose_io.layouts import BODY15

if TYPE_CHECKING:
    import torch

LAYOUT = BODY15
ROOT = "mid_hip"
ROOT_INDEX = LAYOUT.index(ROOT)
# Rows 0-13 of the network input: every body15 joint but the root, in layout order.
LOCAL_JOINTS: tuple[str, ...] = tuple(n for n in LAYOUT.joints if n != ROOT)
LOCAL_INDEX: tuple[int, ...] = tuple(LAYOUT.indices(LOCAL_JOINTS))
NUM_ROWS = len(LOCAL_JOINTS) + 1  # + the root velocity row
NUM_CHANNELS = 2 * NUM_ROWS  # 30
POSE_CHANNELS = 2 * len(LOCAL_JOINTS)  # 28


def _runs(index: tuple[int, ...]) -> tuple[tuple[slice, slice], ...]:
    """(rows, joints) slice pairs of the consecutive runs of ``index`` (row r is joint ``index[r]``)."""
    runs: list[list[int]] = []  # [first row, first joint, length]
    for r, j in enumerate(index):
        if runs and runs[-1][1] + runs[-1][2] == j:
            runs[-1][2] += 1
        else:
            runs.append([r, j, 1])
    return tuple((slice(r, r + n), slice(j, j + n)) for r, j, n in runs)


# LOCAL_INDEX as slices (body15: joints 0-7 and 9-14): whole blocks instead of a gather.
_LOCAL_RUNS = _runs(LOCAL_INDEX)


def complex_points(a: np.ndarray) -> np.ndarray | None:
    """[..., 2] float32/64 coordinates as [...] complex ``x + iy`` (a view), or None where memory or dtype forbid.

    numpy adds and subtracts complex numbers part by part, so a sum of such views is the sums of the
    coordinates bit for bit, in one pass over the frames instead of one strided pass per coordinate (numpy
    broadcasts along a 2-long axis slowly).
    """
    kind = {np.dtype(np.float32): np.complex64, np.dtype(np.float64): np.complex128}.get(a.dtype)
    if kind is None or a.shape[-1:] != (2,) or a.strides[-1] != a.itemsize:
        return None
    try:
        return a.view(kind)[..., 0]
    except ValueError:
        return None



@dataclass(frozen=True)
class PreprocessConfig:
    """How tracks are brought into (and out of) the network's canvas; the authors' demo settings.

    Attributes:
        canvas_height: height of the canvas the network works in; a track is scaled by
            ``canvas_height / image_height``.
        input_sigma: Gaussian smoothing over time (frames) of input tracks after gap filling (0 = off).
        output_sigma: Gaussian smoothing over time of retargeted tracks (0 = off).
        body_height: 0 = scale by the image height (the authors' rule); > 0 = scale every track so that
            its skeleton height (:func:`pose_io.measures.skeleton_height`) is this many canvas pixels.
            The second makes the result independent of the image size, which OpenPose JSON does not
            store and which is then only a guess.
    """

    canvas_height: float = 512.0
    input_sigma: float = 2.0
    output_sigma: float = 2.0
    body_height: float = 0.0


@dataclass(frozen=True, eq=False)
class NormStats:
    """Per-row normalisation statistics of the network input.

    Attributes:
        mean: [15, 2] float64, rows as in the module docstring (14 local joints, then root velocity).
        std: [15, 2] float64, all positive.
    """

    mean: np.ndarray
    std: np.ndarray

    def __post_init__(self) -> None:
        mean = np.array(self.mean, dtype=np.float64)
        std = np.array(self.std, dtype=np.float64)
        if mean.shape != (NUM_ROWS, 2) or std.shape != (NUM_ROWS, 2):
            raise InputError(
                f"normalisation statistics must be [{NUM_ROWS}, 2], got {mean.shape} and {std.shape}"
            )
        if not (np.isfinite(mean).all() and np.isfinite(std).all() and (std > 0).all()):
            raise InputError("normalisation statistics are not finite or have a non-positive std")
        mean.setflags(write=False)
        std.setflags(write=False)
        object.__setattr__(self, "mean", mean)
        object.__setattr__(self, "std", std)

    def channel_tensors(self, like: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """Mean and std as ``[1, 30, 1]`` tensors with ``like``'s dtype and device."""
        import torch

        mean = torch.tensor(self.mean.reshape(1, NUM_CHANNELS, 1), dtype=like.dtype, device=like.device)
        std = torch.tensor(self.std.reshape(1, NUM_CHANNELS, 1), dtype=like.dtype, device=like.device)
        return mean, std

    @property
    def velocity_std(self) -> np.ndarray:
        """[2] std of the root velocity row (pixels per frame)."""
        return self.std[-1]


# The channel functions below take a numpy array or a torch tensor and give back the same kind (and, for a
# tensor, do exactly what they did when they took tensors only).
Array = Any  # np.ndarray | torch.Tensor


def _is_tensor(x: Array) -> bool:
    """Whether ``x`` is a torch tensor, without importing torch (no tensor exists unless torch is loaded)."""
    torch = sys.modules.get("torch")
    return torch is not None and isinstance(x, torch.Tensor)


def _channel_stats(stats: NormStats, like: Array) -> tuple[Array, Array]:
    """Mean and std as ``[1, 30, 1]`` with ``like``'s kind and dtype (and device)."""
    if _is_tensor(like):
        return stats.channel_tensors(like)
    shape = (1, NUM_CHANNELS, 1)
    return stats.mean.reshape(shape).astype(like.dtype), stats.std.reshape(shape).astype(like.dtype)


def _rows(joints: Array) -> Array:
    """[B, T, 15, 2] joints -> [B, T, 15, 2] rows (14 root-relative joints, then root velocity)."""
    root = joints[:, :, ROOT_INDEX]  # [B, T, 2]
    if _is_tensor(joints):
        import torch

        local = joints[:, :, list(LOCAL_INDEX)] - root[:, :, None]  # [B, T, 14, 2]
        velocity = torch.zeros_like(root)
        velocity[:, 1:] = root[:, 1:] - root[:, :-1]
        return torch.cat([local, velocity[:, :, None]], dim=2)
    # The same differences written into one time-major array, run of joints by run of joints (a gather would be
    # one more copy), as points where possible, else a coordinate at a time: the same numbers.
    rows = np.empty((*joints.shape[:2], NUM_ROWS, 2), dtype=np.result_type(joints, root))  # [B, T, 15, 2]
    points, out = complex_points(joints), complex_points(rows)  # [B, T, 15] complex views
    if points is not None and out is not None:
        origin = points[:, :, ROOT_INDEX, None]  # [B, T, 1]
        for in_rows, in_joints in _LOCAL_RUNS:
            np.subtract(points[:, :, in_joints], origin, out=out[:, :, in_rows])
        out[:, :1, -1] = 0
        np.subtract(points[:, 1:, ROOT_INDEX], points[:, :-1, ROOT_INDEX], out=out[:, 1:, -1])
        return rows
    for c in (0, 1):
        origin = root[:, :, None, c]  # [B, T, 1]
        for in_rows, in_joints in _LOCAL_RUNS:
            np.subtract(joints[:, :, in_joints, c], origin, out=rows[:, :, in_rows, c])
        rows[:, :1, -1, c] = 0
        np.subtract(root[:, 1:, c], root[:, :-1, c], out=rows[:, 1:, -1, c])
    return rows


def _rows_in_place(joints: Array) -> np.ndarray | None:
    """:func:`_rows` written over ``joints`` itself, or None when its memory does not allow it.

    Row r is joint ``LOCAL_INDEX[r]`` >= r minus the root: going up from row 0, each joint is read before
    its place is written (the root is copied out first; the velocity row comes last).
    """
    if _is_tensor(joints) or not joints.flags.c_contiguous or not joints.flags.writeable:
        return None
    points = complex_points(joints)  # [B, T, 15]
    if points is None:
        return None
    origin = points[:, :, ROOT_INDEX].copy()  # [B, T]
    for in_rows, in_joints in _LOCAL_RUNS:
        if in_rows == in_joints:
            np.subtract(points[:, :, in_joints], origin[:, :, None], out=points[:, :, in_rows])
            continue
        for r in range(in_rows.start, in_rows.stop):
            np.subtract(points[:, :, in_joints.start + r - in_rows.start], origin, out=points[:, :, r])
    points[:, :1, -1] = 0
    np.subtract(origin[:, 1:], origin[:, :-1], out=points[:, 1:, -1])
    return joints


def joints_to_channels(
    joints: Array, stats: NormStats, overwrite: bool = False, dtype: np.dtype | type | None = None
) -> Array:
    """The normalised network input of body15 poses.

    Args:
        joints: [B, T, 15, 2] body15 coordinates in the network's canvas (no NaN); a tensor or an array.
        stats: normalisation statistics.
        overwrite: ``joints`` may be used as the result's memory (a C-contiguous float array; otherwise
            this is ignored): on long tracks, a track-sized array fewer to allocate and touch.
        dtype: (arrays only) the result's type when not that of ``joints``, e.g. float32 network input of
            float64 poses: computed in ``joints``' type and rounded once, as ``.astype(dtype)`` of the
            result would be, the last operation writing it (no pass over a converted copy).

    Returns:
        [B, 30, T] of the same kind and dtype (or ``dtype``) (channel ``2r + c`` = coordinate ``c`` of row
        ``r``); an array's is a view of a time-major ``[B, T, 30]`` one.
    """
    if dtype is not None and _is_tensor(joints):
        raise TypeError("joints_to_channels: dtype is for numpy arrays; convert a tensor with .to()")
    b, t = joints.shape[:2]
    rows = _rows_in_place(joints) if overwrite else None
    if rows is None:
        rows = _rows(joints)  # [B, T, 15, 2]
    if _is_tensor(rows) or rows.dtype.kind != "f":
        x = rows.reshape(b, t, NUM_CHANNELS).swapaxes(1, 2)  # [B, 30, T]
        mean, std = _channel_stats(stats, x)
        x = (x - mean) / std
        return x if dtype is None else x.astype(dtype)
    # The same element-wise operations, in place on _rows' time-major array; a [B, 30, T] view of it.
    x = rows.reshape(b, t, NUM_CHANNELS)  # [B, T, 30]
    mean, std = _channel_stats(stats, x)
    x -= mean.reshape(1, 1, NUM_CHANNELS)
    out = x if dtype is None or np.dtype(dtype) == x.dtype else np.empty(x.shape, dtype=dtype)
    np.divide(x, std.reshape(1, 1, NUM_CHANNELS), out=out, casting="unsafe")  # the quotient in x's type, rounded
    return out.swapaxes(1, 2)


def channels_to_joints(
    x: Array,
    stats: NormStats,
    start: Array | None = None,
    overwrite: bool = False,
    dtype: np.dtype | type | None = None,
) -> Array:
    """Undo :func:`joints_to_channels`: body15 poses whose root follows the integrated velocity.

    The root of frame ``t`` is ``start + v[0] + ... + v[t]`` (the authors' convention, ``v[0]`` included).

    Args:
        x: [B, 30, T] normalised network output or input; a tensor or an array.
        stats: normalisation statistics.
        start: [B, 2] or [2] start point of the root trajectory; default 0.
        overwrite: ``x`` may be used as the result's memory (a time-major float array, e.g. a
            ``[B, 30, T]`` view of a fresh ``[B, T, 30]`` one; otherwise this is ignored): on long tracks, two
            track-sized arrays fewer to allocate and touch.
        dtype: (arrays only) the type to compute in and return when not ``x``'s, e.g. float64 poses of a
            float32 network output: ``x``'s values are converted as they are read, the numbers of
            ``channels_to_joints(x.astype(dtype), ...)`` without that converted copy.

    Returns:
        [B, T, 15, 2] body15 coordinates in the canvas, of ``x``'s kind and dtype (or ``dtype``).
    """
    b, _, t = x.shape
    if _is_tensor(x):
        import torch

        if dtype is not None:
            raise TypeError("channels_to_joints: dtype is for numpy arrays; convert a tensor with .to()")
        mean, std = _channel_stats(stats, x)
        rows = (x * std + mean).transpose(1, 2).reshape(b, t, NUM_ROWS, 2)  # [B, T, 15, 2]
        root = torch.cumsum(rows[:, :, -1], dim=1)  # [B, T, 2]
        if start is not None:
            root = root + torch.as_tensor(start, dtype=x.dtype, device=x.device).reshape(-1, 1, 2)
        joints = x.new_zeros(b, t, len(LAYOUT), 2)
        joints[:, :, list(LOCAL_INDEX)] = rows[:, :, :-1]
        return joints + root[:, :, None]
    # The same element-wise operations as above, time-major (the network's output is), run of joints by run of
    # joints, as points where possible (numpy broadcasts along a 2-long axis slowly): the same numbers.
    work = x.dtype if dtype is None else np.dtype(dtype)
    shape = (1, 1, NUM_CHANNELS)
    mean, std = (a.reshape(shape).astype(work) for a in (stats.mean, stats.std))  # _channel_stats' numbers
    in_place = overwrite and work == x.dtype and x.dtype.kind == "f" and x.swapaxes(1, 2).flags.c_contiguous
    if in_place:
        rows = x.swapaxes(1, 2)  # [B, T, 30], x's memory
        rows *= std
    else:
        rows = np.multiply(x.swapaxes(1, 2), std, dtype=work, order="C")  # [B, T, 30], a fresh array
    rows += mean
    rows = rows.reshape(b, t, NUM_ROWS, 2)  # [B, T, 15, 2]
    root = np.cumsum(rows[:, :, -1], axis=1)  # [B, T, 2]
    if start is not None:
        root = root + np.asarray(start, dtype=work).reshape(-1, 1, 2)
    if complex_points(rows) is not None and complex_points(root) is not None:  # rows is ours: x's memory, or fresh
        # Rows become joints where they lie: row r goes to joint LOCAL_INDEX[r] >= r, so going down from the
        # last row each one is read before anything is written over it (a run that moves, one row at a time).
        points, origin = complex_points(rows), complex_points(root)  # [B, T, 15], [B, T]
        for in_rows, in_joints in reversed(_LOCAL_RUNS):
            if in_rows == in_joints:
                np.add(points[:, :, in_rows], origin[:, :, None], out=points[:, :, in_joints])
                continue
            for r in range(in_rows.stop - 1, in_rows.start - 1, -1):
                np.add(points[:, :, r], origin, out=points[:, :, in_joints.start + r - in_rows.start])
        np.add(0.0, origin, out=points[:, :, ROOT_INDEX])  # (0 + root, as the zeros above give)
        return rows
    joints = np.empty((b, t, len(LAYOUT), 2), dtype=work)  # not floats: a coordinate at a time
    for c in (0, 1):
        origin = root[:, :, None, c]  # [B, T, 1]
        for in_rows, in_joints in _LOCAL_RUNS:
            np.add(rows[:, :, in_rows, c], origin, out=joints[:, :, in_joints, c])
        np.add(0.0, root[:, :, c], out=joints[:, :, ROOT_INDEX, c])  # (0 + root, as the zeros above give)
    return joints


def pose_channels(x: Array) -> Array:
    """[B, 30, T] -> [B, 28, T], the root-relative pose (what the static encoders see)."""
    return x[:, :POSE_CHANNELS]


def velocity_channels(x: Array) -> Array:
    """[B, 30, T] -> [B, 2, T], the root velocity."""
    return x[:, POSE_CHANNELS:]


def row_statistics(windows: np.ndarray, min_std: float = 1.0) -> NormStats:
    """Normalisation statistics of body15 windows (mean/std of every row over all frames).

    Args:
        windows: [N, T, 15, 2] body15 coordinates in the canvas.
        min_std: floor of the std in canvas pixels: a coordinate that hardly varies in the training data
            (a rigid pelvis seen from the front) must not turn a pixel of detection noise into a huge input.
    """
    rows = _rows(np.asarray(windows, dtype=np.float64))  # [N, T, 15, 2]
    flat = rows.reshape(-1, NUM_ROWS, 2)
    return NormStats(flat.mean(axis=0), np.maximum(flat.std(axis=0), min_std))
