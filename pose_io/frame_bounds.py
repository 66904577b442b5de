"""Where the image is, when a pose file does not say: its size inferred from the joints, and joints far outside
it dropped as outliers (the rules are :func:`pose_io.limits.outlier_mask`).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from pose_io.errors import InputError
from pose_io.layouts import get_layout
from pose_io.limits import MAX_IMAGE_SIDE, Dropped, outlier_mask
from pose_io.people import Detections

_SIZE_STEP = 16


def infer_image_size(detections: Detections) -> tuple[int, int]:
    """(width, height): the smallest multiples of 16 containing every visible coordinate of ``detections``.

    Raises:
        InputError: the joints reach beyond the largest allowed image (16,384 pixels a side).
    """
    maxima = np.zeros(2)
    for frame in detections.people:
        if len(frame):
            xy = frame[..., :2][frame[..., 2] > 0]
            if len(xy):
                maxima = np.maximum(maxima, np.nanmax(xy, axis=0))
    if (maxima + 1 > MAX_IMAGE_SIDE).any():
        raise InputError(
            f"{detections.source}: joints reach ({maxima[0]:.6g}, {maxima[1]:.6g}), beyond the largest allowed "
            f"image ({MAX_IMAGE_SIDE} pixels a side); pass the image size (--size WxH) if the coordinates are pixels"
        )
    w, h = (max(_SIZE_STEP, math.ceil((float(v) + 1) / _SIZE_STEP) * _SIZE_STEP) for v in maxima)
    return w, h


def drop_outliers(detections: Detections, image_size: tuple[int, int] | None) -> tuple[Detections, Dropped]:
    """``detections`` with outlier joints made missing (rules in :mod:`pose_io.limits`), and what was dropped.

    Args:
        detections: everybody in a source.
        image_size: (width, height), or None when it is unknown (to be inferred after this).

    Returns:
        The detections (the same object when nothing was dropped) and a :class:`pose_io.limits.Dropped`.
    """
    counts = detections.counts  # [T]
    if not counts.any():
        return detections, Dropped(0)
    allpeople = np.concatenate([p for p in detections.people if len(p)])  # [N, J, 3]
    xy = np.where((allpeople[..., 2] > 0)[..., None], allpeople[..., :2], np.nan)
    outliers = outlier_mask(xy, image_size)  # [N, J]
    if not outliers.any():
        return detections, Dropped(0)
    n, j = (int(v) for v in np.argwhere(outliers)[0])
    frame_of = np.repeat(np.arange(len(counts)), counts)  # [N]
    names = get_layout(detections.layout).joints
    dropped = Dropped(int(outliers.sum()), int(frame_of[n]), names[j], float(xy[n, j, 0]), float(xy[n, j, 1]))
    allpeople = allpeople.copy()
    allpeople[outliers] = (np.nan, np.nan, 0.0)
    keep = (allpeople[..., 2] > 0).any(axis=1)  # [N] a detection left without any joint goes
    splits = np.cumsum(counts)[:-1]
    people = tuple(p[k] for p, k in zip(np.split(allpeople, splits), np.split(keep, splits)))
    ids = None
    if detections.ids is not None:
        ids = tuple(i[k] for i, k in zip(detections.ids, np.split(keep, splits)))
    return dataclasses.replace(detections, people=people, ids=ids), dropped
