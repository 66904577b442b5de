"""Helpers shared by the train-ref and drive tests: tiny synthetic performers, CLI arguments, fixtures."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest
import torch

from pose_io import BODY15, PoseTrack
from pose_io.writers import write_track

# tests/clone/train_ref/helpers.py -> the folder holding the repository, where ../shared lives.
OFFICIAL_WEIGHTS = Path(__file__).resolve().parents[4] / "shared" / "official_2dmr" / "weights" / "pretrained_full.pth"


def figure_track(frames: int = 24, width: int = 96, height: int = 72, scale: float = 1.0, phase: float = 0.0,
                 fps: float = 25.0) -> PoseTrack:
    """A body15 figure swinging its arms and legs while drifting sideways."""
    base = np.array(
        [[0, -0.62], [0, -0.5], [-0.12, -0.48], [-0.16, -0.3], [-0.17, -0.12], [0.12, -0.48], [0.16, -0.3],
         [0.17, -0.12], [0, 0], [-0.07, 0], [-0.08, 0.2], [-0.08, 0.4], [0.07, 0], [0.08, 0.2], [0.08, 0.4]])
    t = np.arange(frames)[:, None] + phase
    j = np.repeat(base[None], frames, axis=0)
    swing = np.sin(2 * np.pi * t[:, 0] / 12.0)
    for side, sign in (("r", 1.0), ("l", -1.0)):
        j[:, BODY15.index(f"{side}_wrist"), 0] += sign * 0.15 * swing
        j[:, BODY15.index(f"{side}_ankle"), 0] -= sign * 0.1 * swing
    xy = j * 0.6 * height * scale
    xy[..., 0] += width / 2 + 0.15 * width * np.sin(2 * np.pi * t / 40.0)
    xy[..., 1] += height * 0.52
    return PoseTrack(xy.astype(np.float32), np.ones(xy.shape[:2], np.float32), fps, (width, height), "body15")


def render_figure(track: PoseTrack) -> list[np.ndarray]:
    """Frames of ``track``: coloured limbs, torso and head over a checked background, [H, W, 3] uint8."""
    w, h = track.image_size
    yy, xx = np.mgrid[0:h, 0:w]
    background = np.stack([80 + 0 * xx, 120 + 40 * yy // h, 100 + 20 * ((xx // 6 + yy // 6) % 2)], -1)
    frames = []
    for pose in track.joints:
        img = background.astype(np.uint8)

        def at(name: str, p: np.ndarray = pose) -> tuple[int, int]:
            return tuple(round(float(v)) for v in p[BODY15.index(name)])

        torso = np.array([at("r_shoulder"), at("l_shoulder"), at("l_hip"), at("r_hip")], np.int32)
        cv2.fillConvexPoly(img, torso, (220, 180, 40))
        for a, b in BODY15.limbs:
            colour = (40, 60, 190) if "hip" in a or "knee" in a else (200, 40, 40)
            cv2.line(img, at(a), at(b), colour, 3)
        cv2.circle(img, at("nose"), 5, (240, 200, 170), -1)
        frames.append(img)
    return frames


def write_reference(folder: Path, track: PoseTrack, frames: list[np.ndarray] | None = None) -> tuple[Path, Path]:
    """Poses as an OpenPose folder and frames as PNGs; returns (poses, frames folder)."""
    frames = render_figure(track) if frames is None else frames
    frame_dir = folder / "frames"
    frame_dir.mkdir(parents=True)
    for i, f in enumerate(frames):
        cv2.imwrite(str(frame_dir / f"{i:04d}.png"), cv2.cvtColor(f, cv2.COLOR_RGB2BGR))
    poses = write_track(track, folder / "poses")
    return poses, frame_dir


def train_args(poses: Path, frames: Path, out: Path, *extra: str, steps: int = 3) -> list[str]:
    return ["train-ref", str(poses), str(frames), "--out", str(out), "--size", "32", "--steps", str(steps),
            "--threads", "1", "--device", "cpu", *extra]


def one_line_error(result) -> str:
    assert result.exit_code == 2, result.output
    lines = [line for line in result.output.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), result.output
    return lines[0]


@pytest.fixture
def reference(tmp_path: Path) -> tuple[Path, Path]:
    return write_reference(tmp_path / "ref", figure_track())


@pytest.fixture(autouse=True)
def _restore_threads():
    before = torch.get_num_threads()
    yield
    torch.set_num_threads(before)
