"""Retargeting between real pose tracks, where no ground truth exists: what can still be measured.

For every ordered pair (A, B) of real tracks, A's motion is moved onto B by each method and the output is
compared with what it should keep:

* range of motion (:func:`pose_io.measures.amplitude_ratio`, root removed): the output's joints should swing
  as far, relative to the output body's height, as the driver's do relative to the driver's height. Below 1
  the motion is damped. The driver is measured after the same temporal smoothing the output gets
  (``sigma``), so detection jitter, which no retargeting should copy, does not count as motion.
* the highest a wrist gets above the neck, in % of height (driver vs output): the measure that shows a
  damped arm raise.
* proportion error: B's median limb lengths against the output's, in % of B's height (0 = B's proportions kept;
  :func:`pose_io.measures.proportion_error`).
"""

from __future__ import annotations

from collections.abc import Mapping
from itertools import permutations

import numpy as np

from pose_io.clean import smooth_joints
from pose_io.measures import amplitude_ratio, motion_spread, proportion_error, skeleton_height
from pose_io.track import PoseTrack
from retarget.evaluate.config import Method
from retarget.inference.tracks import filled_body15
from retarget.network.preprocess import LAYOUT, ROOT_INDEX


def wrist_rise(joints: np.ndarray, height: float) -> float:
    """Highest a wrist gets above the neck over a track, in % of ``height`` (image y grows downwards).

    Args:
        joints: [T, 15, 2] body15 pixels.
        height: body height in pixels.
    """
    neck = joints[:, LAYOUT.index("neck"), 1]
    wrists = joints[:, LAYOUT.indices(("r_wrist", "l_wrist")), 1]  # [T, 2]
    return float(np.nanmax(neck[:, None] - wrists) / height * 100)


def pair_scores(
    motion: PoseTrack, reference: PoseTrack, output: PoseTrack, sigma: float = 2.0
) -> dict[str, float | dict]:
    """What retargeting ``motion`` onto ``reference`` kept, measured on ``output`` (see the module docstring).

    Args:
        motion: the driver, any layout that gives body15.
        reference: the person the motion was moved onto.
        output: the retargeted track, [T, 15, 2] body15.
        sigma: temporal smoothing (frames) applied to the driver before it is measured.

    Returns:
        ``amplitude`` (output's range of motion over the driver's), ``amplitude_per_joint`` (the same per
        joint, MidHip left out), ``wrist_rise_pct`` and ``driver_wrist_rise_pct`` (:func:`wrist_rise`),
        ``proportion_error_pct`` (:func:`pose_io.measures.proportion_error` against the reference).
    """
    drv = smooth_joints(filled_body15(motion, "motion track"), sigma)
    ref = filled_body15(reference, "reference track")
    out = np.asarray(output.joints, dtype=np.float64)
    h_drv, h_out = (skeleton_height(j, LAYOUT) for j in (drv, out))
    # The root's spread is 0 once it is subtracted: leave it out rather than divide 0 by 0.
    moving = [j for j in range(len(LAYOUT.joints)) if j != ROOT_INDEX]
    per_joint = motion_spread(out, h_out, ROOT_INDEX)[moving] / motion_spread(drv, h_drv, ROOT_INDEX)[moving]
    return {
        "amplitude": amplitude_ratio(out, h_out, drv, h_drv, ROOT_INDEX),
        "amplitude_per_joint": {LAYOUT.joints[j]: round(float(r), 4) for j, r in zip(moving, per_joint)},
        "wrist_rise_pct": wrist_rise(out, h_out),
        "driver_wrist_rise_pct": wrist_rise(drv, h_drv),
        "proportion_error_pct": proportion_error(out, ref, LAYOUT),
    }


def real_pair_results(
    tracks: Mapping[str, PoseTrack], methods: Mapping[str, Method]
) -> dict[str, dict[str, dict[str, float | dict]]]:
    """Scores of every method on every ordered pair of ``tracks``: ``"A -> B" -> method -> scores``."""
    results: dict[str, dict[str, dict[str, float | dict]]] = {}
    for (a, motion), (b, reference) in permutations(tracks.items(), 2):
        results[f"{a} -> {b}"] = {
            name: pair_scores(motion, reference, method(motion, reference)) for name, method in methods.items()
        }
    return results


def markdown_rows(results: Mapping[str, Mapping[str, Mapping]]) -> list[str]:
    """A markdown table of :func:`real_pair_results`."""
    lines = [
        "| pair | method | range of motion vs driver | wrist above neck % (driver) | proportion error % of B |",
        "|---|---|---|---|---|",
    ]
    for pair, rows in results.items():
        for name, r in rows.items():
            lines.append(
                f"| {pair} | {name} | {r['amplitude']:.2f} | {r['wrist_rise_pct']:.1f} "
                f"({r['driver_wrist_rise_pct']:.1f}) | {r['proportion_error_pct']:.1f} |"
            )
    return lines
