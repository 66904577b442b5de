"""Measures of driven pose tracks and generated frames, for `clone report` and `clone demo`.

- :mod:`~clone.metrics.table`: ``METRICS`` (label, unit, better direction and definition of every summary
  number, in the order a report shows them) and ``Scores`` (per-frame curves, summary, details).
- :mod:`~clone.metrics.poses`: limb error, foot skating, jitter, joints outside the image; against ground-truth
  poses the MidHip-aligned pose error (the primary measure), placement and the view check (definitions in
  ``pose_io.compare``, shared with `clone retarget eval`); ``evaluate_track`` runs them on a track.
- :mod:`~clone.metrics.frames`: SSIM/PSNR of generated frames against the true ones, whole and around the person;
  flicker in the person's box.
- :mod:`~clone.metrics.consistency`: pose consistency, MediaPipe on generated frames against the driven poses.
"""

from clone.metrics.frames import FlickerMeter, FrameScorer, frame_pair_scores, frame_scores, person_box
from clone.metrics.poses import (
    contact_window,
    evaluate_track,
    foot_contacts,
    foot_slide,
    gt_pose_scores,
    jitter,
    limb_error,
    outside_frame,
    pose_scores,
    track_gt_scores,
)
from clone.metrics.table import METRICS, MetricInfo, Scores, nan_mean, row_means

__all__ = [
    "METRICS",
    "FlickerMeter",
    "FrameScorer",
    "MetricInfo",
    "Scores",
    "contact_window",
    "evaluate_track",
    "foot_contacts",
    "foot_slide",
    "frame_pair_scores",
    "frame_scores",
    "gt_pose_scores",
    "jitter",
    "limb_error",
    "nan_mean",
    "outside_frame",
    "person_box",
    "pose_scores",
    "row_means",
    "track_gt_scores",
]
