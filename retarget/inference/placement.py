"""Where a person stands in their video (height, root x, ground line) and moving poses there."""

from __future__ import annotations

import contextlib
import warnings
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from pose_io.errors import InputError
from pose_io.measures import foot_points, median_of, skeleton_heights
from retarget.network.preprocess import LAYOUT, ROOT_INDEX, complex_points


@dataclass(frozen=True)
class Placement:
    """Where a person stands in their video, in that video's pixels.

    Attributes:
        height: skeleton height (:func:`pose_io.measures.skeleton_height`).
        root_x: median x of the root (MidHip).
        ground_y: median y of the lower ankle.
    """

    height: float
    root_x: float
    ground_y: float


def placement_of(joints: np.ndarray, name: str = "track") -> Placement:
    """Placement statistics of [T, 15, 2] body15 joints (NaN allowed).

    Raises:
        InputError: the root or both ankles are never seen, or a bone of the height never is.
    """
    height = float(skeleton_heights(np.asarray(joints, dtype=np.float64)[None], LAYOUT)[0])
    root_x, ground_y = _stand(joints)
    if not all(np.isfinite(v) for v in (height, root_x, ground_y)):
        raise InputError(f"{name}: cannot tell where the person stands (root or ankles never detected)")
    return Placement(height, root_x, ground_y)


def _stand(joints: np.ndarray) -> tuple[float, float]:
    """(median root x, median ground line) of [T, 15, 2] body15 joints (NaN allowed; NaN when never seen)."""
    root, ground = joints[:, ROOT_INDEX, 0], foot_points(joints, LAYOUT)[:, 1]
    if not (np.isnan(root).any() or np.isnan(ground).any()):  # the same medians, without nanmedian's overhead
        return float(median_of(root)), float(median_of(ground))
    with _quiet_nan():
        return float(np.nanmedian(root)), float(np.nanmedian(ground))


def place(joints: np.ndarray, target: Placement) -> np.ndarray:
    """Translate a pose sequence so its median root x and median ground line match ``target``.

    Args:
        joints: [T, 15, 2] body15 coordinates (no NaN).
        target: where the person should stand.

    Returns:
        [T, 15, 2] translated copy.
    """
    shift = placement_shift(joints, target)
    return shifted(joints, shift, np.empty(joints.shape, dtype=np.result_type(joints, shift)))


def placement_shift(joints: np.ndarray, target: Placement) -> np.ndarray:
    """[2] float64 translation :func:`place` applies to [T, 15, 2] body15 ``joints`` (no NaN)."""
    root_x, ground_y = _stand(joints)  # the height placement_of would also measure is not needed here
    if not (np.isfinite(root_x) and np.isfinite(ground_y)):
        raise InputError("track: cannot tell where the person stands (root or ankles never detected)")
    return np.array([target.root_x - root_x, target.ground_y - ground_y])


def shifted(joints: np.ndarray, shift: np.ndarray, out: np.ndarray) -> np.ndarray:
    """``joints + shift`` ([..., 2] + [2], summed in their common type) written into ``out`` (e.g. float32:
    the sums rounded once, as ``(joints + shift).astype(out.dtype)``); returns ``out``.

    As points (or one coordinate at a time): numpy broadcasts along a 2-long axis slowly. The same sums.
    """
    points, into = complex_points(joints), complex_points(out)
    if points is not None and into is not None and shift.dtype == np.float64:
        np.add(points, np.complex128(complex(shift[0], shift[1])), out=into, casting="same_kind")  # (not weak)
        return out
    for c in (0, 1):
        np.add(joints[..., c], shift[c], out=out[..., c], casting="same_kind")
    return out


@contextlib.contextmanager
def _quiet_nan() -> Iterator[None]:
    """Silence numpy's all-NaN-slice warnings inside a block (the NaN results are handled)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", category=RuntimeWarning)
        yield
