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

from pose_io.measures import reference_limb_lengths
from pose_io.track import PoseTrack
from retarget.baselines.global_scale import apply_global_scale, scale_stats
from retarget.inference.placement import place, placement_of
from retarget.inference.tracks import body15_track, filled_body15, to_body15
from retarget.network.preprocess import LAYOUT, ROOT, ROOT_INDEX


def _output(joints: np.ndarray, motion: PoseTrack, reference: PoseTrack) -> PoseTrack:
    placed = place(joints, placement_of(to_body15(reference, "reference track").joints, "reference track"))
    return body15_track(placed, motion.fps, reference.image_size)


def global_scale_retarget(
    motion: PoseTrack, reference: PoseTrack, near_fraction: float = 0.1, min_depth_range: float = 0.05
) -> PoseTrack:
    """Everybody Dance Now's global pose normalisation (see :mod:`retarget.baselines.global_scale`), as a baseline.

    The same functions drive ``clone drive --method global-scale``; here the result is also placed like the
    network's output (median root x and ground line of the reference) so all methods compare frame by frame.

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
    source = scale_stats(drv, LAYOUT, band=near_fraction)
    target = scale_stats(ref, LAYOUT, band=near_fraction)
    return _output(apply_global_scale(drv, LAYOUT, source, target, min_span=min_depth_range), motion, reference)


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
    len_d = reference_limb_lengths(drv, LAYOUT, length_quantile)
    len_r = reference_limb_lengths(ref, LAYOUT, length_quantile)
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

