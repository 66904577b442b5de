"""Non-learned retargeting baselines the network is compared with.

* :func:`global_scale_retarget` - the global pose normalisation of Everybody Dance Now (Chan et al.
  2019): one scale and one offset per frame, interpolated between the driver's nearest and farthest
  ankle positions, so the driver's size matches the reference's at both depths.
* :func:`limb_scale_retarget` - naive 2D retargeting by forward kinematics: every limb vector of the
  driver is scaled by the ratio of the reference's to the driver's 2D limb length,
  ``p'_child = p'_parent + (L_ref / L_drv) * (p_child - p_parent)``, walking the tree out from MidHip;
  the root trajectory is scaled by the ratio of the leg lengths. 2D limb lengths shrink with
  foreshortening, so each is measured as a high percentile (``length_quantile``) over the track.

Both return body15 tracks in the reference's pixels, placed like the network's output (median root x and
ground line of the reference), so the three can be compared frame by frame.
"""

from __future__ import annotations

import numpy as np

from pose_io.track import PoseTrack
from retarget.preprocess import (
    LAYOUT,
    ROOT,
    ROOT_INDEX,
    body15_track,
    filled_body15,
    ground_heights,
    place,
    placement_of,
    pose_heights,
    to_body15,
)


def _output(joints: np.ndarray, motion: PoseTrack, reference: PoseTrack) -> PoseTrack:
    placed = place(joints, placement_of(to_body15(reference, "reference track").joints, "reference track"))
    return body15_track(placed, motion.fps, reference.image_size)


def _depth_profile(joints: np.ndarray, near_fraction: float) -> tuple[float, float, float, float]:
    """(far ankle y, near ankle y, pose height at far, pose height at near) of one track.

    The heights are the largest among frames whose ankle is within ``near_fraction`` of the ankle range
    from that end (the tallest pose there is the most upright one).
    """
    ankle = ground_heights(joints)  # [T]
    height = pose_heights(joints)  # [T]
    far, near = float(np.min(ankle)), float(np.max(ankle))
    band = max(near - far, 1e-6) * near_fraction
    h_far = float(np.max(height[ankle <= far + band]))
    h_near = float(np.max(height[ankle >= near - band]))
    return far, near, h_far, h_near


def global_scale_retarget(
    motion: PoseTrack, reference: PoseTrack, near_fraction: float = 0.05, min_depth_range: float = 0.05
) -> PoseTrack:
    """Everybody Dance Now's global pose normalisation.

    For a driver frame whose lower ankle is at height ``y``, with ``a = (y - far_d) / (near_d - far_d)``:
    scale ``s = h_ref_far / h_drv_far + a * (h_ref_near / h_drv_near - h_ref_far / h_drv_far)`` and the
    ankle goes to ``far_r + a * (near_r - far_r)``. When the driver hardly changes depth (ankle range below
    ``min_depth_range`` of its height), one scale from the tallest poses is used.

    Args:
        motion: driver track (any layout convertible to body15).
        reference: reference track.
        near_fraction: share of the ankle range that counts as "at the near/far end".
        min_depth_range: ankle range (relative to height) below which depth is ignored.

    Returns:
        body15 track, ``len(motion)`` frames, in the reference's pixels.
    """
    drv = filled_body15(motion, "motion track")
    ref = filled_body15(reference, "reference track")
    far_d, near_d, hf_d, hn_d = _depth_profile(drv, near_fraction)
    far_r, near_r, hf_r, hn_r = _depth_profile(ref, near_fraction)
    ankle = ground_heights(drv)  # [T]
    if near_d - far_d < min_depth_range * max(hn_d, hf_d):
        alpha = np.zeros_like(ankle)
        hf_d = hn_d = max(hf_d, hn_d)
        hf_r = hn_r = max(hf_r, hn_r)
    else:
        alpha = (ankle - far_d) / (near_d - far_d)
    scale = hf_r / hf_d + alpha * (hn_r / hn_d - hf_r / hf_d)  # [T]
    target_ankle = far_r + alpha * (near_r - far_r)  # [T]
    root_x = drv[:, ROOT_INDEX, 0]
    out = np.empty_like(drv)
    # Horizontal travel scales with the mean scale; the pose itself with the frame's scale.
    out[..., 0] = scale.mean() * (root_x - root_x[0])[:, None] + scale[:, None] * (drv[..., 0] - root_x[:, None])
    out[..., 1] = target_ankle[:, None] + scale[:, None] * (drv[..., 1] - ankle[:, None])
    return _output(out, motion, reference)


def limb_lengths(joints: np.ndarray, quantile: float = 0.95) -> np.ndarray:
    """[T, 15, 2] body15 -> [L] 2D length of every layout limb (``quantile`` over frames)."""
    a, b = LAYOUT.limb_indices.T
    return np.quantile(np.linalg.norm(joints[:, b] - joints[:, a], axis=-1), quantile, axis=0)


def _leg_length(lengths: np.ndarray) -> float:
    names = {frozenset(pair): i for i, pair in enumerate(LAYOUT.limbs)}
    legs = []
    for side in ("r", "l"):
        chain = ((ROOT, f"{side}_hip"), (f"{side}_hip", f"{side}_knee"), (f"{side}_knee", f"{side}_ankle"))
        legs.append(sum(lengths[names[frozenset(p)]] for p in chain))
    return float(np.mean(legs))


def limb_scale_retarget(motion: PoseTrack, reference: PoseTrack, length_quantile: float = 0.95) -> PoseTrack:
    """Naive 2D retargeting: per-limb scaling by forward kinematics from MidHip.

    Args:
        motion: driver track (any layout convertible to body15).
        reference: reference track.
        length_quantile: quantile over frames that measures a 2D limb length.

    Returns:
        body15 track, ``len(motion)`` frames, in the reference's pixels.
    """
    drv = filled_body15(motion, "motion track")
    ref = filled_body15(reference, "reference track")
    len_d = limb_lengths(drv, length_quantile)
    len_r = limb_lengths(ref, length_quantile)
    ratio = len_r / np.maximum(len_d, 1e-6)  # [L]
    root = drv[:, ROOT_INDEX]
    out = np.empty_like(drv)
    out[:, ROOT_INDEX] = root[0] + (_leg_length(len_r) / max(_leg_length(len_d), 1e-6)) * (root - root[0])
    # Walk the limb tree out from the root: each child is placed from its already placed parent.
    edges = [(int(a), int(b), i) for i, (a, b) in enumerate(LAYOUT.limb_indices)]
    done = {ROOT_INDEX}
    while len(done) < len(LAYOUT):
        grown = False
        for a, b, i in edges:
            for parent, child in ((a, b), (b, a)):
                if parent in done and child not in done:
                    out[:, child] = out[:, parent] + ratio[i] * (drv[:, child] - drv[:, parent])
                    done.add(child)
                    grown = True
        if not grown:
            raise ValueError("body15 limbs do not connect every joint to the root")
    return _output(out, motion, reference)

