"""Images of a report: pose panels, skeletons over frames, captioned side-by-side strips and the still PNGs.

All images are [H, W, 3] uint8 RGB.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import cv2
import numpy as np

from clone.report.results import DriverInfo, GroundTruth, MethodResult
from pose_io.draw import blank_canvas, draw_pose
from pose_io.layouts import get_layout

_CAPTION_GREY = 32  # caption strip background
_CAPTION_TEXT = (235, 235, 235)


def pose_panel(joints: np.ndarray, layout: str, image_size: tuple[int, int], height: int) -> np.ndarray:
    """A pose drawn on black, the image scaled to ``height`` rows.

    Args:
        joints: [J, 2] pixel coordinates in an image of ``image_size`` (width, height), NaN where missing.
        layout: their joint layout.
        image_size: (width, height) of that image.
        height: output rows.

    Returns:
        [height, round(width * height / image height), 3] uint8 RGB.
    """
    w, h = image_size
    k = height / h
    canvas = blank_canvas(max(1, round(w * k)), height)
    return draw_pose(canvas, np.asarray(joints, dtype=np.float64) * k, get_layout(layout))


def overlay(frame: np.ndarray, joints: np.ndarray | None, layout: str) -> np.ndarray:
    """A copy of ``frame`` with a pose drawn thinly over it.

    Args:
        frame: [H, W, 3] uint8 RGB.
        joints: [J, 2] pose in the frame's pixels, or None for no pose.
        layout: joint layout of ``joints``.

    Returns:
        [H, W, 3] uint8 RGB; ``frame`` itself is left as it was.
    """
    out = np.array(frame, dtype=np.uint8, order="C", copy=True)  # generator frames may be strided views
    if joints is not None:
        draw_pose(out, joints, get_layout(layout), thickness=max(1, round(min(out.shape[:2]) / 256)))
    return out


def caption_height(height: int) -> int:
    """Rows of the caption strip above panels ``height`` rows tall."""
    return max(22, round(0.1 * height))


def _captioned(panel: np.ndarray, label: str, height: int, bar_height: int) -> np.ndarray:
    """``panel`` resized to ``height`` rows (aspect kept) under a ``bar_height``-row strip with ``label``.

    Returns:
        [bar_height + height, W', 3] uint8 RGB.
    """
    h, w = panel.shape[:2]
    width = max(1, round(w * height / h))
    if (w, h) != (width, height):
        interp = cv2.INTER_AREA if h > height else cv2.INTER_LINEAR
        panel = cv2.resize(panel, (width, height), interpolation=interp)
    bar = np.full((bar_height, width, 3), _CAPTION_GREY, dtype=np.uint8)
    scale = bar_height / 46  # Hershey simplex at 1.0 is ~22 px tall: text fills about half the strip
    (tw, th), _ = cv2.getTextSize(label, cv2.FONT_HERSHEY_SIMPLEX, scale, 1)
    org = (max(4, (width - tw) // 2), (bar_height + th) // 2)
    cv2.putText(bar, label, org, cv2.FONT_HERSHEY_SIMPLEX, scale, _CAPTION_TEXT, 1, cv2.LINE_AA)
    return np.vstack([bar, panel])


def side_by_side(panels: Sequence[np.ndarray], labels: Sequence[str], height: int) -> np.ndarray:
    """Panels next to each other at one height, each under a caption strip.

    Args:
        panels: [H_i, W_i, 3] uint8 RGB images; each is resized to ``height`` rows keeping its aspect.
        labels: one caption per panel.
        height: rows of the image part.

    Returns:
        [height + caption, sum of widths, 3] uint8 RGB, width and height even (H.264 needs them even).
    """
    if len(panels) != len(labels) or not panels:
        raise ValueError(f"side_by_side: {len(panels)} panels for {len(labels)} labels")
    bar_height = caption_height(height)
    out = np.hstack([_captioned(p, label, height, bar_height) for p, label in zip(panels, labels)])
    h, w = out.shape[:2]  # [caption + height, sum W_i, 3]
    return np.pad(out, ((0, h % 2), (0, w % 2), (0, 0)))


def still_indices(num_frames: int, count: int = 4) -> list[int]:
    """``count`` frame indices spread evenly inside ``range(num_frames)``, away from the ends."""
    if num_frames <= 0:
        return []
    count = min(count, num_frames)
    return sorted({round((i + 1) * num_frames / (count + 1) - 0.5) for i in range(count)})


def write_png(path: Path, image: np.ndarray) -> None:
    """Write an [H, W, 3] uint8 RGB image as a PNG; raise OSError when OpenCV cannot."""
    if not cv2.imwrite(str(path), cv2.cvtColor(image, cv2.COLOR_RGB2BGR)):
        raise OSError(f"{path}: could not write PNG")


def still_image(
    t: int, methods: Mapping[str, MethodResult], driver: DriverInfo, gt: GroundTruth | None, height: int
) -> np.ndarray:
    """Frame ``t`` side by side: driver | each method with its skeleton | ground truth with its skeleton.

    Args:
        t: frame index; every method must have a still of it.
        methods: name -> result, in column order.
        driver: what drove the reference.
        gt: the ground truth, if any; its column is shown when it has a still of ``t``.
        height: rows of each panel's image part.

    Returns:
        [height + caption, W, 3] uint8 RGB.
    """
    track = driver.poses
    if t >= track.num_frames:
        raise ValueError(f"still frame {t} is past the driver's {track.num_frames} frames")
    panels = [pose_panel(track.joints[t], track.layout, track.image_size, height)]
    labels = ["Driver"]
    for m in methods.values():
        panels.append(overlay(m.stills[t], m.still_poses.get(t), m.poses.layout))
        labels.append(m.label)
    if gt is not None and t in gt.stills:
        panels.append(overlay(gt.stills[t], gt.still_poses.get(t), gt.layout))
        labels.append("Ground truth")
    return side_by_side(panels, labels, height)


def write_stills(
    stage: Path, methods: Mapping[str, MethodResult], driver: DriverInfo, gt: GroundTruth | None, height: int
) -> list[tuple[int, str]]:
    """One PNG per still frame (``still_image``), named ``still_<frame>.png``.

    The frames shown are those every method has a still of.

    Args:
        stage: the folder to write into.
        methods: name -> result, in column order.
        driver: what drove the reference.
        gt: the ground truth, if any.
        height: rows of each panel's image part.

    Returns:
        (frame index, file name) per still.
    """
    frames = sorted(set.intersection(*(set(m.stills) for m in methods.values()))) if methods else []
    out = []
    for t in frames:
        name = f"still_{t:05d}.png"
        write_png(stage / name, still_image(t, methods, driver, gt, height))
        out.append((t, name))
    return out
