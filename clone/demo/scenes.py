"""The demo's scenes: the built-in motions, the three kinds of performance and the in-frame check.

A pair's ground truth is the reference's character performing the driver's motion, seen by the reference's
camera: ``render_performance`` with the driver's motion window and the reference's character and yaw.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import asdict
from importlib import resources
from pathlib import Path

import numpy as np

from clone.demo.config import DemoConfig, PairConfig
from pose_io.errors import InputError
from pose_io.track import PoseTrack

log = logging.getLogger(__name__)

_MOTIONS = "demo_motions.npz"


def demo_motions() -> dict[str, object]:
    """The built-in motions as ``Motion3D``, by key (``clone/data/SOURCES.md`` says where each comes from).

    ``reference`` and ``driver`` are the two dances of the first demo (CMU 05_18 and 05_19); the others are
    named by what they show.
    """
    from retarget.world import Motion3D

    with resources.as_file(resources.files("clone") / "data" / _MOTIONS) as path:
        data = np.load(path)
        fps = float(data["fps"])
        keys = [k for k in data.files if data[k].ndim == 3]
        return {
            key: Motion3D(positions=data[key].astype(np.float32), fps=fps, name=str(data[f"{key}_name"]),
                          source=f"clone2d built-in demo ({key})")
            for key in keys
        }  # fmt: skip


def _motion(motions: dict[str, object], key: str) -> object:
    if key not in motions:
        raise InputError(f"unknown demo motion {key!r}; valid: {', '.join(motions)}")
    return motions[key]


def ground_truth_track(config: DemoConfig, pair: PairConfig, motions: dict[str, object] | None = None) -> PoseTrack:
    """The exact BODY_25 poses of ``pair``'s ground truth (no frames are rendered)."""
    from clone.synth import get_character
    from clone.synth.performance import render_performance

    motions = motions or demo_motions()
    skeleton, look, _ = get_character(config.reference_character)
    _frames, track, _meta = render_performance(
        _motion(motions, pair.motion), skeleton, look, yaw=config.reference_yaw, size=config.render_size,
        start=pair.start, frames=pair.frames,
    )  # fmt: skip
    return track


def reference_track(config: DemoConfig, motions: dict[str, object] | None = None,
                    size: tuple[int, int] | None = None) -> PoseTrack:
    """The exact BODY_25 poses of the demo's reference video (no frames are rendered); ``size``: in a frame of
    this (width, height) instead of the demo's square one, the camera as far (the body as large)."""
    from clone.synth import get_character
    from clone.synth.performance import render_performance

    skeleton, look, _ = get_character(config.reference_character)
    motion = _motion(motions or demo_motions(), config.reference_motion)
    return render_performance(motion, skeleton, look, yaw=config.reference_yaw, size=size or config.render_size,
                              frames=config.reference_frames)[1]  # fmt: skip


def stays_in_frame(config: DemoConfig, track: PoseTrack) -> bool:
    """Whether every present joint of ``track`` keeps the configured margin from the frame's edges."""
    return edge_distance(track) >= config.edge_margin * config.render_size


def edge_distance(track: PoseTrack) -> float:
    """How close the track comes to the frame's edges: the smallest distance in pixels of any present joint
    in any frame to the nearest edge (pixel centres 0 .. size - 1); negative when a joint is outside."""
    w, h = track.image_size
    joints = track.joints[~track.missing]  # [N, 2]
    if not len(joints):
        raise InputError("the track has no joints")
    x, y = joints[:, 0].astype(np.float64), joints[:, 1].astype(np.float64)
    return float(min(x.min(), y.min(), (w - 1) - x.max(), (h - 1) - y.max()))


def check_in_frame(config: DemoConfig, pair: PairConfig, track: PoseTrack) -> float:
    """Log whether ``pair``'s ground truth stays inside the frame with the configured margin.

    Returns:
        The track's :func:`edge_distance` in pixels.
    """
    margin = config.edge_margin * config.render_size
    distance = edge_distance(track)
    if not stays_in_frame(config, track):
        log.warning("the ground truth of %s comes %.0f px from the frame's edge (less than the %.0f px margin): "
                    "part of the person leaves the frame", pair.name, distance, margin)
    else:
        log.info("the ground truth of %s stays inside the frame (%.0f px from the edges at least)", pair.name,
                 distance)
    return distance


def render_scenes(out: Path, config: DemoConfig, on_start: Callable[[str], None] | None = None) -> dict[str, float]:
    """Render the reference, and every pair's driver and ground truth, into ``out``.

    Layout: ``out/reference/``, ``out/<pair>/driver/``, ``out/<pair>/ground_truth/`` (each as
    ``clone.synth.save_performance`` writes it: frames, poses, poses.npz, meta.json).

    Args:
        out: the demo folder.
        config: what to render.
        on_start: called with a short description as each performance starts.

    Returns:
        Pair name -> its ground truth's :func:`edge_distance` in pixels.
    """
    from clone.synth import get_character, save_performance
    from pose_io.readers import read_track

    motions = demo_motions()
    ref_skeleton, ref_look, _ = get_character(config.reference_character)
    meta = {"config": asdict(config)}

    def render(folder: Path, role: str, motion: str, skeleton, look, yaw: float, start: int, frames: int | None):
        if on_start is not None:
            on_start(f"rendering {folder.relative_to(out)}")
        save_performance(folder, _motion(motions, motion), skeleton, look, yaw=yaw, size=config.render_size,
                         start=start, frames=frames, extra_meta={"demo": {"role": role, **meta}})  # fmt: skip

    render(out / "reference", "reference", config.reference_motion, ref_skeleton, ref_look, config.reference_yaw,
           0, config.reference_frames)  # fmt: skip
    distances = {}
    for pair in config.pairs:
        skeleton, look, _ = get_character(pair.character)
        render(out / pair.name / "driver", "driver", pair.motion, skeleton, look, pair.yaw, pair.start, pair.frames)
        truth = out / pair.name / "ground_truth"
        render(truth, "ground_truth", pair.motion, ref_skeleton, ref_look, config.reference_yaw, pair.start,
               pair.frames)  # fmt: skip
        distances[pair.name] = check_in_frame(config, pair, read_track(truth / "poses.npz"))
    return distances
