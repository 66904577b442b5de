"""One split of a built motion world: its windows replayed on its characters, projected from its views.

``WorldSplit`` opens the split's memory-mapped arrays; 2D views are projected on the fly (cheap), with the
framing rule of ``camera.frame_camera``. A sample is (motion, character, view): motion a window index (64
frames, stride 32), character an index into the split's characters, view an index into ``VIEW_YAWS``.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import NamedTuple

import numpy as np

from pose_io.layouts import BODY15
from retarget.world.camera import (
    AIM_HEIGHT,
    VIEW_YAWS,
    WORLD_CAMERAS,
    Camera,
    CameraSpread,
    facing_angles,
    frame_camera,
    perspective_xy,
    view_rotations,
)
from retarget.world.config import WorldConfig
from retarget.world.skeleton import WORLD_JOINTS, Skeleton

_ROOT = WORLD_JOINTS.index("mid_hip")
_BODY15_IDX = np.array([WORLD_JOINTS.index(n) for n in BODY15.joints], dtype=np.int64)


class WindowLabel(NamedTuple):
    """Where a window comes from."""

    clip: str  # clip name (file stem)
    path: str  # file path relative to the mocap folder
    start: int  # first frame in the clip (at the world's fps)
    group: str  # motion group: takes of one motion share it and always share a split
    clip_frames: int  # frames in the clip: valid offsets are -start .. clip_frames - start - length


class WorldSplit:
    """One split of a motion world: windows x characters x views.

    Attributes:
        name: "train", "val" or "test".
        positions: [C, F, 18, 3] float32 (memory-mapped) every character's replay of every clip,
            clips concatenated along F.
        source_positions: [F, 18, 3] the clips on their own skeletons.
        characters: the C characters.
        window_length: the default window length.
        canvas_size: (width, height) of the 2D views.
    """

    def __init__(self, name: str, folder: Path, meta: dict, config: WorldConfig) -> None:
        self._args = (name, Path(folder), meta, config)
        self.name = name
        info = meta["splits"][name]
        self.positions = np.load(folder / f"{name}_positions.npy", mmap_mode="r")
        self.source_positions = np.load(folder / f"{name}_source.npy", mmap_mode="r")
        self._windows = np.load(folder / f"{name}_windows.npy")
        self._clip_offsets = np.asarray(info["clip_offsets"], dtype=np.int64)
        self._clip_frames = np.asarray(info["clip_frames"], dtype=np.int64)
        self.clips: tuple[dict, ...] = tuple(info["clips"])
        self.characters: tuple[Skeleton, ...] = tuple(
            Skeleton(tuple(c["lengths"]), c["name"]) for c in info["characters"]
        )
        self.window_length = config.window
        self.canvas_size = tuple(config.canvas_size)
        self.views: tuple[float, ...] = VIEW_YAWS
        self.window_labels: tuple[WindowLabel, ...] = tuple(
            WindowLabel(
                self.clips[c]["name"], self.clips[c]["path"], int(s), self.clips[c]["group"], int(self._clip_frames[c])
            )
            for c, s in self._windows
        )

    def __reduce__(self) -> tuple:
        # Pickle the folder, not the memory-mapped arrays: data-loader workers reopen the same files.
        return (WorldSplit, self._args)

    def __repr__(self) -> str:
        return (f"WorldSplit({self.name!r}, motions={self.num_motions}, characters={self.num_characters}, "
                f"views={self.num_views})")

    @property
    def num_motions(self) -> int:
        """Number of windows."""
        return int(self._windows.shape[0])

    @property
    def num_characters(self) -> int:
        return len(self.characters)

    @property
    def num_views(self) -> int:
        return len(self.views)

    @property
    def num_clips(self) -> int:
        return len(self.clips)

    @property
    def character_names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.characters)

    def _frames(self, motion: int, length: int, offset: int) -> slice:
        if not 0 <= motion < self.num_motions:
            raise IndexError(f"{self.name}: motion {motion} out of range 0..{self.num_motions - 1}")
        clip, start = (int(v) for v in self._windows[motion])
        first = start + offset
        if length < 1 or first < 0 or first + length > self._clip_frames[clip]:
            raise ValueError(
                f"{self.name}: frames {first}..{first + length - 1} are outside clip "
                f"{self.clips[clip]['name']} ({self._clip_frames[clip]} frames)"
            )
        base = int(self._clip_offsets[clip]) + first
        return slice(base, base + length)

    def window3d(self, motion: int, character: int, length: int | None = None, offset: int = 0) -> np.ndarray:
        """[length, 18, 3] float32 3D joints of a window on a character, metres, Y up, first root over
        the origin (x = z = 0) and the ground at y = 0.

        Args:
            motion: window index.
            character: character index.
            length: frames (default the world's window); ``offset + length`` must stay inside the clip.
            offset: frames after the window's start.
        """
        if not 0 <= character < self.num_characters:
            raise IndexError(f"{self.name}: character {character} out of range 0..{self.num_characters - 1}")
        frames = self._frames(motion, self.window_length if length is None else length, offset)
        pos = np.array(self.positions[character, frames], dtype=np.float32)
        pos[..., 0] -= pos[0, _ROOT, 0]
        pos[..., 2] -= pos[0, _ROOT, 2]
        return pos

    def camera(self, view: int, pitch_deg: float = 0.0) -> Camera:
        """The framing-rule camera of view bin ``view``."""
        if not 0 <= view < self.num_views:
            raise IndexError(f"view {view} out of range 0..{self.num_views - 1}")
        return frame_camera(self.views[view], pitch_deg, self.canvas_size)

    def window(
        self,
        motion: int,
        character: int,
        view: int,
        length: int | None = None,
        offset: int = 0,
        rng: np.random.Generator | None = None,
        pitch_deg: float | None = None,
        cameras: CameraSpread = WORLD_CAMERAS,
    ) -> np.ndarray:
        """[length, 15, 2] float32 body15 pixels (x right, y down) of a window on a character from a view.

        The view's yaw is relative to the window's average facing; the ground under the window's first
        root lands at (W/2, 0.9 H) (``camera.frame_camera``).

        Args:
            motion: window index.
            character: character index.
            view: view bin (index into ``views``).
            length: frames (default the world's window).
            offset: frames after the window's start.
            rng: draws the camera from ``cameras``; None: pitch 0.
            pitch_deg: an explicit pitch (overrides ``rng``).
            cameras: how ``rng`` draws the camera (default: the world's, pitch in +-``MAX_PITCH`` degrees).
        """
        pitch = None if pitch_deg is None else [pitch_deg]
        return self.windows([motion], [character], [view], length, rng, offset, pitch, cameras)[0]

    def windows(
        self,
        motions: Sequence[int],
        characters: Sequence[int],
        views: Sequence[int],
        length: int | None = None,
        rng: np.random.Generator | None = None,
        offset: int = 0,
        pitch_deg: Sequence[float] | None = None,
        cameras: CameraSpread = WORLD_CAMERAS,
    ) -> np.ndarray:
        """[B, length, 15, 2] float32: ``window`` for B (motion, character, view) triples at once.

        Args:
            motions, characters, views: [B] indices.
            length: frames (default the world's window).
            rng: draws each camera from ``cameras``; None: pitch 0.
            offset: frames after each window's start.
            pitch_deg: [B] explicit pitches (override ``rng``).
            cameras: how ``rng`` draws cameras (default: the world's, pitch in +-``MAX_PITCH``).
        """
        if not len(motions) == len(characters) == len(views):
            raise ValueError("motions, characters and views must have the same length")
        views_a = np.asarray(views, dtype=np.int64)
        if ((views_a < 0) | (views_a >= self.num_views)).any():
            raise IndexError(f"views must be in 0..{self.num_views - 1}")
        pos = np.stack([self.window3d(m, c, length, offset) for m, c in zip(motions, characters)])  # [B, L, 18, 3]
        return self.project(pos, views_a, rng, pitch_deg, cameras)

    def project(
        self,
        pos: np.ndarray,
        views: Sequence[int] | np.ndarray,
        rng: np.random.Generator | None = None,
        pitch_deg: Sequence[float] | None = None,
        cameras: CameraSpread = WORLD_CAMERAS,
    ) -> np.ndarray:
        """[B, L, 18, 3] world joints (as ``window3d`` gives them) -> [B, L, 15, 2] float32 body15 pixels.

        The camera and framing rule of ``windows``: each clip's yaw is relative to its own average facing,
        the ground under its first root lands at (W/2, 0.9 H).

        Args:
            pos: [B, L, 18, 3] metres, first root over the origin, ground at y = 0.
            views: [B] view bins.
            rng: draws each camera from ``cameras`` (pitch, and distance when it has perspective); None:
                pitch 0, weak perspective.
            pitch_deg: [B] explicit pitches (override ``rng``'s; weak perspective).
            cameras: how ``rng`` draws the cameras (default: the world's, pitch in +-``MAX_PITCH``).
        """
        b = len(pos)
        views_a = np.asarray(views, dtype=np.int64)
        distance = np.full(b, np.inf)
        if pitch_deg is not None:
            pitch = np.asarray(pitch_deg, dtype=np.float64).reshape(b)
        elif rng is not None:
            pitch, distance = cameras.draw(rng, b)
        else:
            pitch = np.zeros(b)
        yaw = np.asarray(self.views, dtype=np.float64)[views_a] + facing_angles(pos)
        rot = view_rotations(yaw, pitch)  # [B, 3, 3]
        pts = pos[:, :, _BODY15_IDX, None, :]  # [B, L, 15, 1, 3]
        if np.isfinite(distance).any():
            cam3 = (rot[:, None, None].astype(np.float32) * pts).sum(axis=-1)  # [B, L, 15, 3]
            aim = rot @ np.array([0.0, AIM_HEIGHT, 0.0])  # [B, 3]
            cam = perspective_xy(cam3, aim, distance).astype(np.float32)
        else:  # only camera x and y are needed
            cam = (rot[:, None, None, :2, :].astype(np.float32) * pts).sum(axis=-1)  # [B, L, 15, 2] metres, y up
        ref = frame_camera(0.0, 0.0, self.canvas_size)
        cam *= np.float32(ref.scale)
        cam[..., 0] += np.float32(ref.tx)
        cam[..., 1] = np.float32(ref.ty) - cam[..., 1]
        return cam


__all__ = ["WindowLabel", "WorldSplit"]
