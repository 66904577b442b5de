"""Tiny data for the report tests: a stepping body15 figure, frames of it and measured methods."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from clone import metrics
from clone.report.panels import side_by_side, still_indices
from clone.report.results import DriverInfo, GroundTruth, MethodResult
from pose_io import BODY15, PoseTrack, measures
from pose_io.draw import draw_pose

SIZE = 64  # reference frames are SIZE x SIZE
T = 32

_STAND = {
    "nose": (32, 12), "neck": (32, 18), "r_shoulder": (27, 18), "r_elbow": (25, 27), "r_wrist": (24, 35),
    "l_shoulder": (37, 18), "l_elbow": (39, 27), "l_wrist": (40, 35), "mid_hip": (32, 36), "r_hip": (29, 36),
    "r_knee": (29, 46), "r_ankle": (29, 56), "l_hip": (35, 36), "l_knee": (35, 46), "l_ankle": (35, 56),
}  # fmt: skip


def walk(frames: int = T, scale: float = 1.0, size: int = SIZE) -> PoseTrack:
    """A body15 figure swinging its arms and stepping in place, in a size x size image at 30 fps."""
    base = np.array([_STAND[n] for n in BODY15.joints], dtype=np.float64)
    t = np.arange(frames)[:, None]
    joints = np.repeat(base[None], frames, axis=0)
    joints[:, BODY15.indices(["r_wrist", "l_wrist"]), 0] += 4 * np.sin(t / 3)
    joints[:, BODY15.index("r_ankle"), 1] -= np.clip(3 * np.sin(t / 2), 0, None)[:, 0]
    joints = (joints - [32, 56]) * scale + [size / 2, size * 56 / 64]
    return PoseTrack(joints, np.ones(joints.shape[:2]), 30.0, (size, size), "body15")


def frame_of(joints: np.ndarray, size: int = SIZE) -> np.ndarray:
    """[size, size, 3] uint8 RGB: the [J, 2] body15 pose drawn on a grey-blue background."""
    img = np.full((size, size, 3), (70, 80, 100), dtype=np.uint8)
    return draw_pose(img, joints, BODY15, thickness=2)


def make_methods(
    frames: int = 12, with_frames: bool = True
) -> tuple[dict[str, MethodResult], DriverInfo, GroundTruth]:
    """Two methods driving a figure: "global-scale" the truth moved 3 px to the right (the right pose in the wrong
    place), "retarget" equal to it."""
    driver = walk(frames, 0.8)
    truth = walk(frames)
    ref = measures.reference_limb_lengths(truth.joints)
    height = measures.skeleton_height(truth.joints)
    at = still_indices(frames, 3)
    methods = {}
    for name, label, shift in (("global-scale", "Global scaling", 3.0), ("retarget", "Retargeted", 0.0)):
        track = truth.replace(joints=truth.joints + [shift, 0])
        scores = metrics.evaluate_track(track, ref, height, truth)
        if with_frames:
            pred = [frame_of(j) for j in track.joints]
            scores = scores.merged(
                metrics.frame_scores(pred, [frame_of(j) for j in truth.joints], truth.joints)
            )
        stills = {t: frame_of(track.joints[t]) for t in at}
        methods[name] = MethodResult(label, track, scores, stills, {t: track.joints[t] for t in at}, "x")
    info = DriverInfo(driver, "drv/poses.npz", "ref_model.pt", None)
    gt = GroundTruth("gt/poses", "gt/frames", {t: frame_of(truth.joints[t]) for t in at},
                     {t: truth.joints[t] for t in at})  # fmt: skip
    return methods, info, gt


def write_video(path: Path, frames: int = 12) -> Path:
    """A two-panel side-by-side mp4 of the walking figure."""
    from pose_io.video_out import VideoWriter

    with VideoWriter(path, fps=30) as video:
        for j in walk(frames).joints:
            video.write(side_by_side([frame_of(j), frame_of(j)], ["a", "b"], SIZE))
    return path


def write_gt(tmp_path: Path, frames: int = T, size: int = SIZE) -> tuple[Path, Path]:
    """Ground truth of the walking figure: its poses as .npz and its frames as a folder of PNGs."""
    from pose_io.writers import write_track

    truth = walk(frames, size=size)
    poses = write_track(truth, tmp_path / "gt_poses.npz")
    folder = tmp_path / "gt_frames"
    folder.mkdir()
    for t, j in enumerate(truth.joints):
        cv2.imwrite(str(folder / f"frame_{t:04d}.png"), cv2.cvtColor(frame_of(j, size), cv2.COLOR_RGB2BGR))
    return poses, folder
