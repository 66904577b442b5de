"""Whole performances: a motion replayed on a character, framed by the framing rule, rendered and saved.

:func:`render_performance` gives a lazy stream of frames, the exact projected BODY_25 poses and a meta
dict; :func:`save_performance` writes them into a folder, atomically. The per-frame work stays well above
20 frames/s at 256² on one core (buffers are allocated once per video).
"""

from __future__ import annotations

import dataclasses
import json
import logging
import os
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from pathlib import Path

import cv2
import numpy as np

from clone.synth.appearance import Look
from clone.synth.background import floor_line, make_background
from clone.synth.body import PerformerRenderer
from clone.synth.details import detail_track
from pose_io.atomic import atomic_dir, check_new_output
from pose_io.layouts import BODY25
from pose_io.track import PoseTrack
from pose_io.writers import write_track
from retarget.world.camera import (
    FRAME_GROUND,
    FRAME_SCALE,
    Camera,
    facing_angle,
    frame_camera,
    ground_origin,
    project,
)
from retarget.world.skeleton import WORLD_JOINTS, Motion3D, Skeleton, retarget_3d
from retarget.world.turns import Turn, apply_turn

logger = logging.getLogger(__name__)


def _canvas_size(size: int | tuple[int, int]) -> tuple[int, int]:
    w, h = (size, size) if isinstance(size, (int, np.integer)) else size
    if int(w) < 16 or int(h) < 16:
        raise ValueError(f"canvas size must be at least 16 x 16 pixels, got {w} x {h}")
    return int(w), int(h)


def render_frames(xy: np.ndarray, depth: np.ndarray, px_per_m: float, look: Look, size: tuple[int, int],
                  joint_names: Sequence[str], floor_y: float) -> Iterator[np.ndarray]:
    """Render a sequence of projected poses, one frame at a time (memory stays bounded).

    Args:
        xy: [T, K, 2] pixel coordinates.
        depth: [T, K] metres, larger is farther.
        px_per_m: pixels per metre.
        look: appearance.
        size: (width, height).
        joint_names: the K joint names.
        floor_y: image row of the backdrop's floor line.

    Yields:
        [H, W, 3] uint8 RGB frames (each a new array).
    """
    w, h = size
    renderer = PerformerRenderer(look, make_background(w, h, look.backdrop, floor_y), joint_names)
    for t in range(xy.shape[0]):
        yield renderer.render(xy[t], depth[t], px_per_m, out=np.empty((h, w, 3), dtype=np.uint8))


def body25_track(xy: np.ndarray, joint_names: Sequence[str], fps: float, size: tuple[int, int]) -> PoseTrack:
    """A BODY_25 track of projected joints: joints with the same name copied, the others missing.

    Args:
        xy: [T, K, 2] pixel coordinates.
        joint_names: the K names (e.g. ``WORLD_JOINTS``).
        fps: frame rate.
        size: (width, height) of the canvas.
    """
    layout = BODY25
    joints = np.full((xy.shape[0], len(layout), 2), np.nan, dtype=np.float32)
    for k, name in enumerate(joint_names):
        if layout.has(name):
            joints[:, layout.index(name)] = xy[:, k]
    conf = np.where(np.isnan(joints[..., 0]), 0.0, 1.0).astype(np.float32)
    return PoseTrack(joints, conf, fps, size, layout.name)


def _performance_meta(motion: Motion3D, skeleton: Skeleton, look: Look, camera: Camera, facing: float,
                      start: int, stop: int, size: tuple[int, int], floor_y: float) -> dict:
    """The JSON-ready description of a render (see :func:`render_performance`)."""
    return {
        "motion": {"name": motion.name, "source": motion.source, "fps": motion.fps, "start": start,
                   "frames": int(stop - start), "total_frames": motion.num_frames},
        "character": {"skeleton": skeleton.name, "look": look.name, "height_m": skeleton.height,
                      "bone_lengths_m": skeleton.as_dict()},
        "camera": dataclasses.asdict(camera),
        "facing_deg": facing,
        "framing": {
            "rule": "retarget_3d on the whole motion, cut frames, yaw relative to the clip's mean facing, "
                    "ground under the clip's first root at (W/2, FRAME_GROUND*H), FRAME_SCALE*H px per metre",
            "FRAME_GROUND": FRAME_GROUND, "FRAME_SCALE": FRAME_SCALE,
        },
        "size": list(size),
        "fps": motion.fps,
        "floor_y": floor_y,
        "look": look.to_dict(),
    }


def render_performance(
    motion: Motion3D,
    skeleton: Skeleton,
    look: Look,
    yaw: float,
    pitch: float = 0.0,
    size: int | tuple[int, int] = 256,
    start: int = 0,
    frames: int | None = None,
    turn: Turn | None = None,
    details: bool = False,
) -> tuple[Iterator[np.ndarray], PoseTrack, dict]:
    """Render ``motion`` performed by a character (``skeleton`` + ``look``) from a view.

    The fixed rule, so that rendering the reference character with the driver's motion and the
    reference's view is exactly the ground truth of a cloning run:

    1. the whole motion is replayed on ``skeleton`` (:func:`retarget.world.skeleton.retarget_3d`);
    2. frames ``start : start + frames`` are kept (the rendered clip);
    3. the view yaw is relative to the clip's average facing (:func:`retarget.world.camera.facing_angle`);
    4. framing (:func:`retarget.world.camera.frame_camera`): the ground under the clip's first root is at
       (W/2, 0.9 H) and the scale is 0.36 H pixels per metre.

    Args:
        motion: the motion (any character; it is retargeted).
        skeleton: bone lengths of the performer.
        look: appearance of the performer.
        yaw: view yaw in degrees (0 = front, +90 = the performer's left side).
        pitch: camera elevation in degrees (+ = from above).
        size: canvas side (square) or (width, height) in pixels.
        start: first frame of the clip.
        frames: number of frames (default: to the end).
        turn: a whole-body turn added to the clip after step 2 (:func:`retarget.world.turns.apply_turn`); the
            view's yaw stays relative to the clip's facing before it, so the camera is where it would be.
        details: give the body31 track with the face, hand and heel points where the renderer draws them
            (:func:`clone.synth.details.detail_track`) instead of the BODY_25 one.

    Returns:
        ``(frames, track, meta)``: an iterator of [H, W, 3] uint8 RGB frames, the BODY_25 (or body31)
        :class:`PoseTrack` of the exact projected joints, and a JSON-ready dict describing the render.
    """
    w, h = _canvas_size(size)
    total = motion.num_frames
    if not 0 <= start < total:
        raise ValueError(f"start frame {start} is outside the motion's {total} frames")
    stop = total if frames is None else start + int(frames)
    if frames is not None and (frames < 1 or stop > total):
        raise ValueError(f"frames {start}..{stop - 1} are outside the motion's {total} frames")
    positions = retarget_3d(motion, skeleton).positions[start:stop]  # [T, 18, 3] metres, Y up
    facing = facing_angle(positions)
    if turn is not None:
        positions = apply_turn(positions, turn)
    camera = frame_camera(yaw, pitch, (w, h))
    xy, depth = project(positions, camera, facing, origin=ground_origin(positions))  # [T, 18, 2], [T, 18]
    if details:
        track = detail_track(xy, depth, camera.scale, WORLD_JOINTS, look.shape, motion.fps, (w, h))
    else:
        track = body25_track(xy, WORLD_JOINTS, motion.fps, (w, h))
    floor_y = floor_line(camera.ty, camera.scale, h, pitch)
    meta = _performance_meta(motion, skeleton, look, camera, facing, start, stop, (w, h), floor_y)
    return render_frames(xy, depth, camera.scale, look, (w, h), WORLD_JOINTS, floor_y), track, meta


def performance_background(look: Look, yaw: float, pitch: float = 0.0, size: int | tuple[int, int] = 256
                           ) -> np.ndarray:
    """The empty background of a performance as it appears in its video: what every frame shows where the
    performer is not (the ground truth of a background plate).

    Args:
        look: appearance of the performer (its backdrop).
        yaw, pitch, size: as for :func:`render_performance` (the framing rule places the floor line).

    Returns:
        [H, W, 3] uint8 RGB.
    """
    w, h = _canvas_size(size)
    camera = frame_camera(yaw, pitch, (w, h))
    return make_background(w, h, look.backdrop, floor_line(camera.ty, camera.scale, h, pitch))


def _merge_meta(meta: dict, extra: Mapping[str, Mapping] | None) -> None:
    """Update ``meta`` with ``extra`` in place: a dict value is merged into the section of that name."""
    for key, value in (extra or {}).items():
        if isinstance(value, Mapping) and isinstance(meta.get(key), dict):
            meta[key].update(value)
        else:
            meta[key] = value


def _in_canvas(track: PoseTrack) -> np.ndarray:
    """[T, J] bool: joints inside the canvas (pixel centres 0 .. size - 1)."""
    w, h = track.image_size
    inside = (track.joints[..., 0] >= 0) & (track.joints[..., 1] >= 0)
    inside &= (track.joints[..., 0] <= w - 1) & (track.joints[..., 1] <= h - 1)
    return inside


def _write_frames(folder: Path, frames: Iterable[np.ndarray], on_frame: Callable[[int], None] | None) -> None:
    """Write [H, W, 3] uint8 RGB ``frames`` as ``folder/frame_000000.png ...``."""
    folder.mkdir()
    for t, frame in enumerate(frames):
        path = folder / f"frame_{t:06d}.png"
        if not cv2.imwrite(str(path), np.ascontiguousarray(frame[..., ::-1])):  # OpenCV wants BGR
            raise OSError(f"{path}: could not write the PNG")
        if on_frame is not None:
            on_frame(t)


def save_performance(
    out: str | os.PathLike,
    motion: Motion3D,
    skeleton: Skeleton,
    look: Look,
    yaw: float,
    pitch: float = 0.0,
    size: int | tuple[int, int] = 256,
    start: int = 0,
    frames: int | None = None,
    overwrite: bool = False,
    extra_meta: Mapping[str, Mapping] | None = None,
    on_frame: Callable[[int], None] | None = None,
) -> Path:
    """Render a performance (see :func:`render_performance`) into a folder, atomically.

    Writes ``out/frames/frame_000000.png ...`` (RGB PNG), ``out/poses/`` (OpenPose BODY_25 JSON, one
    file per frame, of the projected joints; joints the world does not define and joints outside the
    canvas are written as missing, as a detector could not see them), ``out/poses.npz`` (the same track
    with every projected joint, also outside the canvas) and ``out/meta.json`` (the ``meta`` of
    :func:`render_performance`, updated with ``extra_meta`` section by section).

    Args:
        out: output folder; must not exist unless ``overwrite``.
        motion, skeleton, look, yaw, pitch, size, start, frames: as for :func:`render_performance`.
        overwrite: replace an existing ``out`` (only once the new one is complete).
        extra_meta: more entries for ``meta.json``; a dict value is merged into the section of that name.
        on_frame: called with the frame index after each frame is written (progress display).

    Returns:
        ``out``.
    """
    out = Path(out)
    check_new_output(out, overwrite)
    frame_iter, track, meta = render_performance(motion, skeleton, look, yaw, pitch, size, start, frames)
    _merge_meta(meta, extra_meta)
    inside = _in_canvas(track)
    seen = track.replace(confidence=np.where(inside, track.confidence, 0.0))
    with atomic_dir(out, overwrite=overwrite) as tmp:
        _write_frames(tmp / "frames", frame_iter, on_frame)
        write_track(seen, tmp / "poses", fmt="openpose")
        write_track(track, tmp / "poses.npz")
        meta["files"] = {"frames": "frames/frame_%06d.png", "poses": "poses/ (OpenPose BODY_25, in-canvas joints)",
                         "poses_npz": "poses.npz (every projected joint)"}
        meta["joints_outside_canvas"] = int((~inside & ~track.missing).sum())
        (tmp / "meta.json").write_text(json.dumps(meta, indent=1) + "\n")
    logger.info("wrote %s (%d frames)", out, track.num_frames)
    return out
