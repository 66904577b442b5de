"""What a report's numbers are: the table of measures (label, unit, better direction, definition) and ``Scores``.

Every summary key that ``clone.metrics`` produces has an entry in :data:`METRICS`, in the order a report shows
them: the pose error without placement first (the primary measure), then placement, the view check, the frame
measures, the paper's error and PCK, and the measures that need no ground truth.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np


@dataclass(frozen=True)
class MetricInfo:
    """What one summary number means: its label, unit, which direction is better (None: neither, it only
    describes the motion), and its definition."""

    label: str
    unit: str
    better: Literal["lower", "higher"] | None
    meaning: str
    scale: float = 1.0  # multiply by this for display (e.g. MSE in height² shown x 1000)


_ALIGNED = "after subtracting each frame's MidHip from both (placement removed), as `clone retarget eval`"

# Summary keys, in the order a report shows them.
METRICS: dict[str, MetricInfo] = {
    "pose_rmse_pct": MetricInfo(
        "Pose error (MidHip-aligned)", "% of height", "lower",
        f"root mean squared distance between driven and true joints {_ALIGNED}; the primary pose measure",
    ),
    "root_rmse_pct": MetricInfo(
        "Placement (root error)", "% of height", "lower",
        "root mean squared distance between the driven and the true MidHip: where the body stands",
    ),
    "facing_share": MetricInfo(
        "Faces the true side", "share of frames", "higher",
        "share of frames in which the driven body faces the same side of the image as the truth (the sign of "
        "the nose's horizontal offset from the neck); frames where the truth is seen nearly from the front or "
        "the back (offset under 1 % of the height) are left out",
    ),
    "ssim_crop": MetricInfo(
        "SSIM (person)", "", "higher", "SSIM of a crop around the true pose's box plus 15 % margin"
    ),
    "psnr_crop": MetricInfo("PSNR (person)", "dB", "higher", "PSNR of the same crop around the person"),
    "psnr_background": MetricInfo(
        "PSNR (background)", "dB", "higher",
        "PSNR of every pixel outside that crop, where the true frame shows only the scene (squared error pooled "
        "over all frames)",
    ),
    "ssim": MetricInfo("SSIM (frame)", "", "higher", "structural similarity of the whole frame to the true frame"),
    "psnr": MetricInfo(
        "PSNR (frame)", "dB", "higher", "peak signal-to-noise ratio of the whole frame (inf when identical)"
    ),
    "consistency_pck": MetricInfo(
        "Pose seen in the frames (PCK@0.1)", "share of joints", "higher",
        "MediaPipe run on the generated frames against the poses they were made from: share of body15 joints "
        "it finds within 10 % of the height (a joint it does not find counts as missed); says whether the "
        "frames show the pose asked for, whatever the pose",
    ),
    "consistency_median_pct": MetricInfo(
        "Pose seen in the frames: median error", "% of height", "lower",
        "median distance between the joints MediaPipe finds in the generated frames and the driven ones",
    ),
    "flicker": MetricInfo(
        "Flicker (person)", "levels / frame", None,
        "mean absolute change (8-bit levels) from each generated frame to the next inside the driven pose's "
        "box plus 15 %: motion and flicker alike, so compare with the true video's (flicker ratio)",
    ),
    "flicker_ratio": MetricInfo(
        "Flicker against the truth", "x the true video's", None,
        "the flicker above over the true frames' own in the true pose's box: 1 changes as much as the real "
        "video, above 1 flickers more",
    ),
    "pose_mse": MetricInfo(
        "Pose MSE (paper)", "height² x 10³", "lower",
        f"the paper's error: mean over frames, joints and both coordinates of ((driven - true) / height)² "
        f"{_ALIGNED}; shown x 1000",
        1000.0,
    ),
    "pck_0.05": MetricInfo(
        "PCK@0.05", "share", "higher", f"share of joints within 5 % of the height of the truth, {_ALIGNED}"
    ),
    "pck_0.1": MetricInfo(
        "PCK@0.1", "share", "higher", f"share of joints within 10 % of the height of the truth, {_ALIGNED}"
    ),
    "limb_error_pct": MetricInfo(
        "Limb-length error", "% of height", "lower",
        "mean over frames and limbs of |driven limb length - the reference's median length of that limb|",
    ),
    "jitter_pct": MetricInfo(
        "Jitter", "% of height / frame²", "lower",
        "mean norm of every joint's second difference x[t+1] - 2 x[t] + x[t-1] (acceleration)",
    ),
    "foot_slide_pct": MetricInfo(
        "Foot skating", "% of height / frame", "lower",
        "mean horizontal move of an ankle between two frames in which it touches the ground (near its lowest "
        "point within about a second, moving little vertically)",
    ),
    "foot_slide_px": MetricInfo("Foot skating (px)", "px / frame", "lower", "foot skating in pixels of the image"),
    "contact_share": MetricInfo(
        "Ankle contact", "share of ankle-frames", None, "share of ankle-frames judged to touch the ground"
    ),
    "outside_share": MetricInfo("Joints outside frame", "share", "lower", "share of joints outside the image"),
    "novelty_pct": MetricInfo(
        "Distance to the reference's poses", "% of height", "lower",
        "distance of each driven pose (relative to the MidHip) to the nearest pose the reference showed in its "
        "video (clone.drive.coverage): the generator was never shown poses far from all of them",
    ),
    "uncovered_share": MetricInfo(
        "Outside the reference's coverage", "share of frames", "lower",
        "share of frames whose pose is further from every reference pose than the reference's own poses are "
        "from each other (clone.drive.coverage): expect holes and smears there",
    ),
    "stage_share": MetricInfo(
        "Moved onto the stage", "share of frames", None,
        "share of frames whose root or feet lay off the part of the frame the reference used in its video, so "
        "the whole track was moved onto it (clone.drive.stage)",
    ),
}  # fmt: skip


@dataclass(frozen=True)
class Scores:
    """Per-frame curves and summary numbers of a set of measures of one track or video.

    Attributes:
        per_frame: name -> [T] float64 values, NaN where a frame has no value.
        summary: name -> one number (keys of ``METRICS``).
        details: name -> small JSON-able extras (e.g. the per-limb error).
    """

    per_frame: dict[str, np.ndarray] = field(default_factory=dict)
    summary: dict[str, float] = field(default_factory=dict)
    details: dict[str, object] = field(default_factory=dict)

    def merged(self, other: Scores) -> Scores:
        """Both sets of measures in one (``other`` wins on equal names)."""
        return Scores(
            {**self.per_frame, **other.per_frame},
            {**self.summary, **other.summary},
            {**self.details, **other.details},
        )


def nan_mean(values: np.ndarray) -> float:
    """Mean of the finite-or-inf values, NaN ignored; NaN when there are none."""
    values = np.asarray(values, dtype=np.float64)
    values = values[~np.isnan(values)]
    return float(values.mean()) if values.size else float("nan")


def row_means(values: np.ndarray) -> np.ndarray:
    """[T] mean of each row of [T, K] values, NaN ignored; NaN for a row with no value."""
    values = np.asarray(values, dtype=np.float64)
    count = (~np.isnan(values)).sum(axis=1)
    sums = np.nansum(values, axis=1)
    return np.divide(sums, count, out=np.full(count.shape, np.nan), where=count > 0)
