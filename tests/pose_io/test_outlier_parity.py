"""The linear-time outlier rule (pose_io.limits.outlier_mask) flags exactly the joints the sorting one did."""

from __future__ import annotations

import numpy as np
import pytest

from pose_io.limits import (
    BODY_PER_SPREAD,
    MIN_BODY_JOINTS,
    OUTLIER_BODY_SIZES,
    OUTLIER_IMAGE_MARGIN,
    _row_nanmedian,
    outlier_mask,
)


def _sorted_row_nanmedian(a: np.ndarray) -> np.ndarray:
    """The implementation before the partitions (a full sort per row), kept as the reference."""
    ordered = np.sort(a, axis=1)
    count = (~np.isnan(a)).sum(axis=1, keepdims=True)
    lo = np.take_along_axis(ordered, np.maximum(count - 1, 0) // 2, axis=1)
    hi = np.take_along_axis(ordered, np.minimum(count // 2, a.shape[1] - 1), axis=1)
    return np.where(count > 0, 0.5 * (lo + hi), np.nan)[:, 0]


def _reference_mask(xy: np.ndarray, image_size: tuple[int, int] | None) -> np.ndarray:
    """outlier_mask as it was before the fast paths (same rules, sorts, no early exit)."""
    xy = np.asarray(xy, dtype=np.float64)
    visible = ~np.isnan(xy).any(axis=-1)
    out = np.zeros(visible.shape, dtype=bool)
    if not visible.any():
        return out
    centre = _sorted_row_nanmedian(xy)
    dist = np.linalg.norm(xy - centre[:, None], axis=-1)
    spread = _sorted_row_nanmedian(dist)
    judged = visible.sum(axis=1) >= MIN_BODY_JOINTS
    body = BODY_PER_SPREAD * float(np.median(spread[judged])) if judged.any() else 0.0
    with np.errstate(invalid="ignore"):
        near_body = judged[:, None] & (dist <= OUTLIER_BODY_SIZES * max(body, 1.0))
    if image_size is not None:
        lo, hi = np.zeros(2), np.array(image_size, dtype=np.float64)
    else:
        anchor = visible & near_body
        if not anchor.any():
            return out
        lo, hi = xy[anchor].min(axis=0), xy[anchor].max(axis=0)
    margin = OUTLIER_IMAGE_MARGIN * max(float((hi - lo).max()), 1.0)
    with np.errstate(invalid="ignore"):
        far_image = ((xy < lo - margin) | (xy > hi + margin)).any(axis=-1)
    return visible & far_image & ~near_body


def _random_poses(rng: np.random.Generator, frames: int, joints: int, size: tuple[int, int]) -> np.ndarray:
    """[T, J, 2] float32 bodies walking in an image, with missing joints, outliers and half-missing pairs."""
    w, h = size
    centre = np.stack([rng.uniform(0, w, frames), rng.uniform(0, h, frames)], axis=1)  # [T, 2]
    body = rng.normal(0, rng.uniform(1, max(2.0, 0.2 * h)), (frames, joints, 2))
    xy = (centre[:, None] + body).astype(np.float32)
    xy[rng.random((frames, joints)) < rng.uniform(0, 0.6)] = np.nan  # missing joints
    far = rng.random((frames, joints)) < 0.02
    xy[far] = rng.choice([-1, 1], (far.sum(), 2)) * rng.uniform(0.5, 30, (far.sum(), 2)) * max(w, h)
    xy[rng.random(frames) < 0.1] = np.nan  # frames without anybody
    half = rng.random((frames, joints)) < 0.01
    xy[half, rng.integers(0, 2)] = np.nan  # one coordinate missing: not visible
    if frames > 3 and rng.random() < 0.3:
        xy[: frames // 3, : joints // 2] += np.float32(3 * max(w, h))  # a whole pose far off the frame
    return xy


@pytest.mark.parametrize("seed", range(60))
def test_outlier_mask_flags_the_same_joints_as_the_sorting_rule(seed):
    rng = np.random.default_rng(seed)
    frames = int(rng.choice([1, 2, 3, 5, 17, 120, 700]))
    joints = int(rng.choice([1, 2, 3, 15, 18, 25, 33]))
    size = (int(rng.integers(16, 2000)), int(rng.integers(16, 2000)))
    xy = _random_poses(rng, frames, joints, size)
    for image_size in (size, None):
        for values in (xy, xy.astype(np.float64)):
            np.testing.assert_array_equal(outlier_mask(values, image_size), _reference_mask(values, image_size))


def test_outlier_mask_takes_lists_ints_and_all_missing_poses():
    xy = [[[10, 10], [12, 40], [9, 80], [100_000, 10]]]
    np.testing.assert_array_equal(outlier_mask(xy, (64, 96)), [[False, False, False, True]])
    np.testing.assert_array_equal(outlier_mask(np.array(xy), None), _reference_mask(np.array(xy), None))
    empty = np.full((4, 3, 2), np.nan, dtype=np.float32)
    assert not outlier_mask(empty, (64, 64)).any() and not outlier_mask(empty, None).any()


@pytest.mark.parametrize("seed", range(20))
def test_row_nanmedian_is_the_sorted_middle(seed):
    rng = np.random.default_rng(100 + seed)
    a = rng.normal(size=(int(rng.integers(1, 300)), int(rng.integers(1, 40))))
    a[rng.random(a.shape) < rng.uniform(0, 1)] = np.nan
    a[rng.random(a.shape) < 0.1] = 3.0  # ties
    if seed % 3 == 0:
        a[:, -1] = np.nan  # no row complete
    np.testing.assert_array_equal(_row_nanmedian(a), _sorted_row_nanmedian(a))
    np.testing.assert_array_equal(_row_nanmedian(a[:, ::-1].T), _sorted_row_nanmedian(a[:, ::-1].T))  # strided
