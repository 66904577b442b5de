"""Body measures of 2D pose tracks: one definition of each, used by retargeting, evaluation and reports.

Small pure numpy functions on ``[T, J, 2]`` pixel arrays (NaN where a joint is missing) and a joint layout;
every joint is found by name.
"""

from __future__ import annotations

import functools
import logging

import numpy as np

from pose_io.errors import InputError
from pose_io.layouts import JointLayout, get_layout

log = logging.getLogger(__name__)

# The ankle pair, in the order every per-foot array uses.
ANKLES: tuple[str, ...] = ("l_ankle", "r_ankle")

# segment_lengths of up to this many coordinates go through one transposed copy (fewest calls), longer ones
# segment by segment (no track-sized temporaries: on 10,000 frames the copy's fresh pages cost more than it saved).
_PLANES_UP_TO = 65_536

# The bones whose lengths add up to a standing height: head, trunk, and the two legs (averaged).
_HEIGHT_BONES: tuple[tuple[str, str], ...] = (("nose", "neck"), ("neck", "mid_hip")) + tuple(
    (f"{s}_{a}", f"{s}_{b}") for s in ("l", "r") for a, b in (("hip", "knee"), ("knee", "ankle"))
)


def as_layout(layout: JointLayout | str) -> JointLayout:
    """A layout from its name, or the layout itself."""
    return get_layout(layout) if isinstance(layout, str) else layout


def check_joints(joints: np.ndarray, layout: JointLayout, what: str) -> np.ndarray:
    """``joints`` as float64 ``[T, J, 2]`` for ``layout``; InputError naming ``what`` otherwise."""
    joints = np.asarray(joints, dtype=np.float64)
    if joints.ndim != 3 or joints.shape[1:] != (len(layout), 2):
        raise InputError(f"{what}: expected [T, {len(layout)}, 2] joints for {layout.name}, got {joints.shape}")
    return joints


def segment_lengths(joints: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    """Lengths of joint-to-joint segments.

    Args:
        joints: [..., J, 2] pixel coordinates, NaN where missing.
        pairs: [L, 2] joint index pairs.

    Returns:
        [..., L] float64 lengths, NaN where either end is missing.
    """
    joints = np.asarray(joints, dtype=np.float64)
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    if joints.shape[-1] != 2:
        return np.linalg.norm(joints[..., pairs[:, 0], :] - joints[..., pairs[:, 1], :], axis=-1)
    # sqrt(dx² + dy²) is np.linalg.norm's sum of two squares to the bit, without its slow 2-long reduction.
    if joints.size > _PLANES_UP_TO:  # a long track: segment by segment, no temporary the size of the track
        out = np.empty((*joints.shape[:-2], len(pairs)))
        for i, (a, b) in enumerate(pairs.tolist()):
            dx = joints[..., a, 0] - joints[..., b, 0]
            dy = joints[..., a, 1] - joints[..., b, 1]
            dx *= dx
            dy *= dy
            dx += dy
            np.sqrt(dx, out=out[..., i])
        return out
    # Short: contiguous coordinate planes [J, 2, ...] (one transposing copy), fewest numpy calls.
    lead = tuple(range(joints.ndim - 2))
    planes = np.ascontiguousarray(joints.transpose(joints.ndim - 2, joints.ndim - 1, *lead))  # [J, 2, ...]
    d = planes[pairs[:, 0]] - planes[pairs[:, 1]]  # [L, 2, ...]
    lengths = np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1])  # [L, ...]
    return lengths.transpose(*(a + 1 for a in lead), 0)  # [..., L]


def foot_points(joints: np.ndarray, layout: JointLayout) -> np.ndarray:
    """The lower ankle of each frame (the foot on the ground).

    Args:
        joints: [T, J, 2] image pixels, NaN where missing.
        layout: layout of ``joints`` (must have ``l_ankle`` and ``r_ankle``).

    Returns:
        [T, 2]; NaN where both ankles are missing.
    """
    left, right = (joints[:, i] for i in layout.indices(ANKLES))  # [T, 2] each
    y_left, y_right = (np.where(np.isnan(a[:, 1]), -np.inf, a[:, 1]) for a in (left, right))  # [T]
    right_lower = y_right > y_left  # [T]; a tie goes to the first ankle, as an argmax would
    out = np.empty((len(joints), 2), dtype=np.float64)
    for c in (0, 1):  # per coordinate: no slow 2-long axes
        out[:, c] = np.where(right_lower, right[:, c], left[:, c])
    out[~(np.isfinite(y_left) | np.isfinite(y_right))] = np.nan
    return out


def apparent_heights(joints: np.ndarray, foot_y: np.ndarray) -> np.ndarray:
    """Per-frame height: from the topmost visible joint down to the lower ankle.

    Args:
        joints: [T, J, 2] image pixels, NaN where missing.
        foot_y: [T] lower-ankle y.

    Returns:
        [T]; NaN where the foot is missing.
    """
    y = joints[..., 1].astype(np.float64)  # [T, J]
    top = np.min(np.where(np.isnan(y), np.inf, y), axis=1)  # [T]
    return np.where(np.isfinite(top) & np.isfinite(foot_y), foot_y - top, np.nan)


def limb_lengths(joints: np.ndarray, layout: JointLayout | str = "body15") -> np.ndarray:
    """[T, L] length of every limb of ``layout`` (in ``layout.limbs`` order) in every frame of [T, J, 2] joints."""
    layout = as_layout(layout)
    return segment_lengths(check_joints(joints, layout, "limb lengths"), layout.limb_indices)


def reference_limb_lengths(
    joints: np.ndarray, layout: JointLayout | str = "body15", quantile: float = 0.5
) -> np.ndarray:
    """[L] a person's length of every limb: a quantile (the median by default) over the frames of [T, J, 2] joints.

    A high quantile estimates the unforeshortened 2D length. A limb missing in every frame gets NaN (and is
    then left out of limb errors), with a warning.
    """
    layout = as_layout(layout)
    lengths = limb_lengths(joints, layout)
    seen = ~np.isnan(lengths).all(axis=0)
    if not seen.all():
        names = [f"{a}-{b}" for (a, b), ok in zip(layout.limbs, seen) if not ok]
        log.warning("limbs never seen, left out of the limb error: %s", ", ".join(names))
    out = np.full(lengths.shape[1], np.nan)
    out[seen] = np.nanquantile(lengths[:, seen], quantile, axis=0)
    return out


def skeleton_heights(joints: np.ndarray, layout: JointLayout | str = "body15") -> np.ndarray:
    """Standing height of each window of a batch, from its median bone lengths.

    nose-neck + neck-mid_hip + (hip-knee + knee-ankle, mean of the two legs). Bone lengths rather than the
    bounding box, so the height does not change when the person crouches, leans or turns.

    Args:
        joints: [N, T, J, 2] pixel coordinates, NaN where missing.
        layout: a layout with nose, neck, mid_hip, hips, knees and ankles (body15, body25).

    Returns:
        [N] float64 heights, NaN for a window where a bone is missing in every frame.
    """
    layout = as_layout(layout)
    lengths = segment_lengths(joints, _height_pairs(layout.name, layout.joints))  # [N, T, 6]
    missing = np.isnan(lengths)  # [N, T, 6]
    seen = ~missing.all(axis=1)  # [N, 6]
    bones = np.full(lengths.shape[::2], np.nan)  # [N, 6]
    for n in range(len(lengths)):
        if seen[n].all():
            # np.median is nanmedian's result when nothing is missing (tested), minus its masked-array overhead
            gaps = missing[n].any()
            bones[n] = np.nanmedian(lengths[n], axis=0) if gaps else median_of(lengths[n])
    return bones[:, 0] + bones[:, 1] + 0.5 * bones[:, 2:].sum(axis=1)


@functools.lru_cache(maxsize=32)
def _height_pairs(name: str, joints: tuple[str, ...]) -> np.ndarray:
    """[6, 2] joint index pairs of the height's bones in a layout (cached: layouts are data)."""
    index = {n: i for i, n in enumerate(joints)}
    try:
        pairs = np.array([[index[a], index[b]] for a, b in _HEIGHT_BONES])
    except KeyError as exc:  # what layout.index would say
        raise KeyError(f"layout {name} has no joint {exc.args[0]!r}; joints: {', '.join(joints)}") from None
    pairs.setflags(write=False)  # shared by every call
    return pairs


def median_of(values: np.ndarray, axis: int = 0) -> np.ndarray:
    """``np.median(values, axis)`` of a float array without NaN, to the bit, at a fraction of its overhead.

    The same partition around the middle and the same mean of the middle value(s) as ``np.median``, without
    its generic checks (a single track's measures call it a few times; for 120 frames that overhead is most
    of the time). NaN must be handled by the caller (``np.nanmedian``).
    """
    n = values.shape[axis]
    if n == 0:
        return np.median(values, axis=axis)
    k = n // 2
    middle = slice(k, k + 1) if n % 2 else slice(k - 1, k + 1)
    part = np.partition(values, [middle.start, middle.stop - 1] if n % 2 == 0 else k, axis=axis)
    # np.mean of the middle value(s): their sum divided by their count, in the array's float type
    return np.add.reduce(part[(slice(None),) * (axis % values.ndim) + (middle,)], axis=axis) / (2 - n % 2)


def skeleton_height(joints: np.ndarray, layout: JointLayout | str = "body15") -> float:
    """Standing height of one track in pixels (see :func:`skeleton_heights`).

    Args:
        joints: [T, J, 2] pixel coordinates, NaN where missing.
        layout: a layout with nose, neck, mid_hip, hips, knees and ankles.

    Raises:
        InputError: a bone needed for the height is missing in every frame.
    """
    layout = as_layout(layout)
    joints = check_joints(joints, layout, "skeleton height")
    height = float(skeleton_heights(joints[None], layout)[0])
    if not np.isfinite(height) or height <= 0:
        raise InputError("skeleton height: head, trunk or leg bones are missing in every frame")
    return height


def motion_spread(joints: np.ndarray, height: float, root: int | None = None) -> np.ndarray:
    """Range of motion of every joint: the RMS distance from its mean position, in units of ``height``.

    Args:
        joints: [T, J, 2] pixels, NaN where missing.
        height: body height in pixels (e.g. :func:`skeleton_height`).
        root: index of a joint to subtract from every joint first (the body's own motion without its
            travel), or None to keep the travel.

    Returns:
        [J] float64 spreads (NaN for a joint never seen; 0 for the root itself when subtracted).
    """
    joints = np.asarray(joints, dtype=np.float64)
    if root is not None:
        joints = joints - joints[:, root : root + 1]
    seen = ~np.isnan(joints[..., 0]).all(axis=0)
    out = np.full(joints.shape[1], np.nan)
    if seen.any():
        centred = joints[:, seen] - np.nanmean(joints[:, seen], axis=0)
        out[seen] = np.sqrt(np.nanmean((centred**2).sum(axis=-1), axis=0)) / height
    return out


def amplitude_ratio(joints: np.ndarray, height: float, like: np.ndarray, like_height: float,
                    root: int | None = None) -> float:
    """How much ``joints`` move compared with ``like``: the ratio of their summed :func:`motion_spread`.

    1 = the same range of motion (relative to each body's height); below 1 = damped, above = exaggerated.

    Args:
        joints: [T, J, 2] pixels of the track measured.
        height: its body height in pixels.
        like: [T', J, 2] pixels of the track compared with (the driver, or the ground truth).
        like_height: its body height in pixels.
        root: see :func:`motion_spread`.
    """
    mine = motion_spread(joints, height, root)
    theirs = motion_spread(like, like_height, root)
    both = ~np.isnan(mine) & ~np.isnan(theirs)
    total = float(theirs[both].sum())
    return float(mine[both].sum()) / total if total > 0 else float("nan")


def proportion_error(
    joints: np.ndarray, reference: np.ndarray, layout: JointLayout | str = "body15"
) -> float:
    """How far a track's body proportions are from a reference's, in % of the reference's height.

    The mean over limbs of ``|median length - the reference's median length|`` (:func:`reference_limb_lengths`),
    over :func:`skeleton_height` of ``reference`` times 100; 0 means the reference's proportions are kept. One
    number per track, unlike the per-frame limb error of ``clone.metrics.limb_error``; limbs never seen are left out.

    Args:
        joints: [T, J, 2] the track measured.
        reference: [T', J, 2] the reference's joints (any length).
        layout: the layout of both.
    """
    limbs = np.abs(reference_limb_lengths(joints, layout) - reference_limb_lengths(reference, layout))  # [L]
    return float(np.nanmean(limbs) / skeleton_height(reference, layout) * 100)
