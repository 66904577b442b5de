"""Pose tracks the benchmarks run on: the authors' OpenPose example when present, else a synthetic one."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from pose_io.track import PoseTrack

log = logging.getLogger(__name__)

TALL_MAN = Path(__file__).resolve().parents[2] / "shared" / "openpose_examples" / "tall_man"


def synthetic_track() -> PoseTrack:
    """The built-in demo's driver motion projected by the motion world (body25, 256², no frames rendered)."""
    from clone.demo import demo_motions
    from clone.synth import get_character, render_performance

    skeleton, look, _ = get_character("short_stocky")
    _, track, _ = render_performance(demo_motions()["driver"], skeleton, look, yaw=-35.0, size=256)
    return track


def source_track() -> tuple[PoseTrack, str]:
    """(track, where it came from): tall_man's OpenPose JSON when the shared folder is here, else synthetic."""
    if TALL_MAN.is_dir():
        from pose_io.readers import read_track

        return read_track(TALL_MAN), f"OpenPose example {TALL_MAN.name} (720x720)"
    return synthetic_track(), "synthetic (demo driver motion, motion world projection)"


def tiled(track: PoseTrack, frames: int) -> PoseTrack:
    """``track`` played forwards then backwards until it has ``frames`` frames (no jumps at the seams)."""
    order = np.concatenate([np.arange(track.num_frames), np.arange(track.num_frames - 2, 0, -1)])
    idx = np.resize(order, frames)  # [frames] indices into track
    return track.replace(joints=track.joints[idx], confidence=track.confidence[idx])
