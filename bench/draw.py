"""Stage `draw`: ``pose_io.draw.draw_pose`` frames/s at 512².

Baseline: the same limbs and joints with plain per-limb ``cv2.line`` + ``cv2.circle`` at integer
coordinates, 8-connected (no anti-aliasing, no sub-pixel shift), same thickness, radius and colours; it
is the least work OpenCV can do for the same picture, so the ratio is the cost of anti-aliasing, sub-pixel
coordinates and our NaN / clamping handling. Every variant clears the canvas first, as a video loop would.
"""

from __future__ import annotations

from typing import Any

import cv2
import numpy as np

from bench.data import source_track
from bench.harness import row, time_call

SIZE = 512


def _naive(canvas: np.ndarray, joints: np.ndarray, layout: Any, thickness: int) -> np.ndarray:
    """Integer coordinates, LINE_8: the plainest drawing of the same skeleton ([J, 2] joints, no NaN)."""
    pts = [tuple(round(v) for v in p) for p in joints]
    for a, b in layout.limb_indices:
        cv2.line(canvas, pts[a], pts[b], layout.colors[b], thickness, cv2.LINE_8)
    radius = round(max(1.0, thickness * 1.2))
    for j, p in enumerate(pts):
        cv2.circle(canvas, p, radius, layout.colors[j], -1, cv2.LINE_8)
    return canvas


def run(quick: bool = False, repeats: int | None = None, **_: object) -> dict[str, Any]:
    from pose_io.draw import draw_pose

    source, origin = source_track()
    track = source.to_layout("body15")  # complete in every frame (body25 lacks feet here)
    # Fit the poses into a 512² canvas (uniform scale), dropping frames with a missing joint for the naive
    # drawer, which has no NaN handling; all variants draw the same frames.
    full = ~np.isnan(track.joints).any(axis=(1, 2))
    joints = track.joints[full] * (SIZE / max(track.image_size))  # [N, 25, 2]
    layout = track.joint_layout
    thickness = max(1, round(SIZE / 128))
    canvas = np.zeros((SIZE, SIZE, 3), np.uint8)
    n = len(joints)
    reps = repeats or (3 if quick else 7)

    def loop(draw: Any) -> Any:
        def call() -> None:
            for j in joints:
                canvas[:] = 0
                draw(canvas, j)
        return call

    base = time_call(loop(lambda c, j: _naive(c, j, layout, thickness)), reps, 1).rate(n)
    plain = "per-limb cv2.line + cv2.circle, integer coords, LINE_8"
    rows = [
        row("512x512, body15", "draw_pose (anti-aliased, default)", time_call(loop(
            lambda c, j: draw_pose(c, j, layout)), reps, 1).rate(n), "frames/s", base, plain),
        row("512x512, body15", "draw_pose(antialias=False)", time_call(loop(
            lambda c, j: draw_pose(c, j, layout, antialias=False)), reps, 1).rate(n), "frames/s", base, plain),
        row("512x512, body15", "canvas clear only", time_call(loop(lambda c, j: None), reps, 1).rate(n),
            "frames/s", base, plain),
    ]
    return {"rows": rows, "notes": [f"input: {origin}; {n} complete frames per sample, canvas cleared per frame"]}
