"""The reference's data: its poses and frames read and checked, the frames cut to the canvas and kept in a
frame store, training batches, and what the model file records about the reference (summary, codes, scale).

Frames are ``[S, S, 3]`` uint8 RGB on the canvas; joints are canvas pixels with NaN where missing.
"""

from __future__ import annotations

import contextlib
import logging
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import torch
from torch import Tensor

from clone.choices import Align
from clone.model.background import PlateConfig, estimate_plate
from clone.model.canvas import render_pose_map
from clone.model.exemplar import ExemplarBank, training_choices
from clone.model.face import face_mask, face_radius, standing_height
from clone.model.reference import LAYOUT, file_sha256
from clone.model.tensors import to_tensor
from pose_io.errors import InputError
from pose_io.layouts import get_layout
from pose_io.measures import reference_limb_lengths
from pose_io.track import PoseTrack
from retarget.baselines.global_scale import ScaleStats, scale_stats

if TYPE_CHECKING:
    from pose_io.video import Frames

log = logging.getLogger(__name__)

ALIGN_MODES = tuple(a.value for a in Align)
# Frames are kept in memory up to this many bytes, beyond that in a temporary memory-mapped file.
_IN_MEMORY_BYTES = 1 << 30


def usable_frames(track: PoseTrack, min_visible: int) -> np.ndarray:
    """[T] bool: frames with at least ``min_visible`` visible joints."""
    return (~track.missing).sum(axis=1) >= min_visible


class ReferenceData:
    """The reference's frames on the canvas and its poses in canvas pixels.

    Attributes:
        frames: [N, S, S, 3] uint8 RGB (in memory or memory-mapped).
        joints: [N, J, 2] float32 canvas pixels in ``layout`` (the pose maps'), NaN where missing.
        usable: [N] bool, frames trained on.
        size: S.
        plate: [S, S, 3] uint8 RGB background plate, or None (see :func:`reference_plate`).
        layout: the joints' layout (body15, or body31 with the details).
        face_radius: radius of the face's disc each batch carries as ``face`` (:func:`face_mask`), or None: no
            face points, or ``faces=False`` (no loss uses it).
        height: the body's standing height in canvas pixels, or None (the scale of ``AugmentConfig.pose_jitter``).
        exemplars: the bank the generator's exemplars come from (:meth:`set_exemplars`), or None: no exemplars.
        exemplar_choices: [N, k] each frame's candidate bank frames (-1: none), with ``exemplars``.
    """

    def __init__(self, frames: np.ndarray, joints: np.ndarray, usable: np.ndarray, size: int,
                 plate: np.ndarray | None = None, layout: str = LAYOUT, faces: bool = True) -> None:
        self.frames = frames
        self.joints = joints
        self.usable = usable
        self.size = size
        self.plate = plate
        self.layout = get_layout(layout)
        self.indices = np.flatnonzero(usable)
        # The face's disc only where a loss uses it (it is drawn and warped with every sample).
        self.face_radius = face_radius(joints, self.layout) if faces else None
        self.height = standing_height(joints, self.layout)
        self.exemplars: ExemplarBank | None = None
        self.exemplar_choices: np.ndarray | None = None

    def groups(self) -> np.ndarray | None:
        """[N] int, which clip each frame belongs to (an exemplar comes from the frame's own), or None: one."""
        return None

    def set_exemplars(self, bank: ExemplarBank, gap: int) -> None:
        """Give every batch exemplars from ``bank``: for each frame one of its nearest bank frames at least
        ``gap`` frames away (:func:`clone.model.exemplar.training_choices`)."""
        self.exemplars = bank
        self.exemplar_choices = training_choices(bank, self.joints, gap, groups=self.groups())

    def exemplar(self, i: int, k: int, mirrored: bool = False, drop: int = -1) -> np.ndarray:
        """[S, S, 3] uint8 bank frame ``k`` laid onto frame ``i``'s pose (black for i < 0 or k < 0), flipped
        left-right when ``mirrored``; ``drop`` >= 0: black along that limb too
        (:meth:`clone.model.exemplar.ExemplarBank.exemplar`)."""
        if i < 0 or k < 0 or self.exemplars is None:
            return np.zeros((self.size, self.size, 3), dtype=np.uint8)
        image = self.exemplars.exemplar(k, self.joints[i], () if drop < 0 else (drop,))
        return image[:, ::-1] if mirrored else image

    def frame_joints(self, i: int, mirrored: bool = False) -> np.ndarray:
        """[J, 2] frame ``i``'s joints on the canvas; ``mirrored``: as they are in the frame flipped left-right
        (x mirrored, left and right joints swapped, as a pose estimator would label the flipped person)."""
        joints = self.joints[i]
        if not mirrored:
            return joints
        joints = joints[self.layout.mirror].copy()
        joints[:, 0] = (self.size - 1) - joints[:, 0]
        return joints

    def pose_map(self, i: int, offset: np.ndarray | None = None, mirrored: bool = False) -> np.ndarray:
        """[S, S, 3] uint8 pose map of frame ``i`` (black for i < 0), its joints moved by ``offset`` [J, 2]
        (after mirroring, when ``mirrored``)."""
        if i < 0:
            return np.zeros((self.size, self.size, 3), dtype=np.uint8)
        joints = self.frame_joints(i, mirrored)
        if offset is not None:
            joints = joints + offset
        return render_pose_map(joints, self.size, self.layout)

    def frame(self, i: int, mirrored: bool = False) -> np.ndarray:
        """[S, S, 3] uint8 frame ``i`` (flipped left-right when ``mirrored``)."""
        return self.frames[i][:, ::-1] if mirrored else self.frames[i]

    def batch(self, idx: np.ndarray, offsets: np.ndarray | None = None,
              mirror: np.ndarray | None = None, exemplar_pick: np.ndarray | None = None,
              exemplar_drop: np.ndarray | None = None) -> dict[str, Tensor]:
        """Tensors for frames ``idx`` and their predecessors; ``offsets`` [B, J, 2] moves the joints of sample
        b's two pose maps (not its frames or face disc) by ``offsets[b]`` canvas pixels; ``mirror`` [B] bool
        flips sample b left-right (frames, plate, face disc; its pose maps drawn from :meth:`frame_joints`);
        ``exemplar_pick`` [B] int: which of its candidate exemplars sample b gets (default the nearest);
        ``exemplar_drop`` [B] int: the limb its exemplar is blacked out along (-1, the default: none).

        Returns:
            ``pose_prev``, ``pose_cur``, ``frame_prev``, ``frame_cur``: [B, 3, S, S] in [-1, 1] (the previous
            frame of frame 0 is zeros); ``has_prev``: [B] bool; with a plate, ``plate``: [B, 3, S, S] (one
            copy per sample: each is warped with its sample); with exemplars, ``exemplar_prev`` and
            ``exemplar_cur``: [B, 3, S, S], the sample's one bank frame laid onto each of its two poses.
        """
        prev = self.previous(idx)
        zero = np.zeros((self.size, self.size, 3), dtype=np.uint8)
        flips = [False] * len(idx) if mirror is None else [bool(m) for m in mirror]
        has_prev = torch.from_numpy(prev >= 0)
        frame_prev = to_tensor(np.stack([self.frame(p, f) if p >= 0 else zero for p, f in zip(prev, flips)]))
        frame_prev[~has_prev] = 0.0
        moved = [None] * len(idx) if offsets is None else list(offsets)
        sample = {
            "pose_prev": to_tensor(np.stack([self.pose_map(int(p), o, f) for p, o, f in zip(prev, moved, flips)])),
            "pose_cur": to_tensor(np.stack([self.pose_map(int(i), o, f) for i, o, f in zip(idx, moved, flips)])),
            "frame_prev": frame_prev,
            "frame_cur": to_tensor(np.stack([self.frame(i, f) for i, f in zip(idx, flips)])),
            "has_prev": has_prev,
        }
        if self.exemplar_choices is not None:
            picks = np.zeros(len(idx), np.int64) if exemplar_pick is None else np.asarray(exemplar_pick)
            ks = self.exemplar_choices[idx, picks]
            ks = np.where(ks < 0, self.exemplar_choices[idx, 0], ks)  # fewer candidates than asked: the nearest
            drops = np.full(len(idx), -1) if exemplar_drop is None else np.asarray(exemplar_drop)
            sample["exemplar_prev"] = to_tensor(np.stack([self.exemplar(int(p), int(k), f, int(d))
                                                          for p, k, f, d in zip(prev, ks, flips, drops)]))
            sample["exemplar_cur"] = to_tensor(np.stack([self.exemplar(int(i), int(k), f, int(d))
                                                         for i, k, f, d in zip(idx, ks, flips, drops)]))
        plates = self.plates(idx)
        if plates is not None:
            flipped = torch.tensor(flips)
            if bool(flipped.any()):
                plates = plates.clone()
                plates[flipped] = plates[flipped].flip(-1)
            sample["plate"] = plates
        if self.face_radius is not None:
            faces = np.stack([face_mask(self.frame_joints(i, f), self.layout, self.face_radius, self.size)
                              for i, f in zip(idx, flips)])
            sample["face"] = torch.from_numpy(faces[:, None].astype(np.float32))  # [B, 1, S, S]
        return sample

    def previous(self, idx: np.ndarray) -> np.ndarray:
        """[B] the frame before each of ``idx`` (-1: none)."""
        return idx - 1

    def plates(self, idx: np.ndarray) -> Tensor | None:
        """[B, 3, S, S] the background plate of each of ``idx`` in [-1, 1] (one copy per sample: each is warped
        with its sample), or None without a plate."""
        if self.plate is None:
            return None
        return to_tensor(self.plate[None]).repeat(len(idx), 1, 1, 1)


def reference_plate(data: ReferenceData, config: PlateConfig) -> np.ndarray:
    """The background plate of the reference on the canvas (:func:`clone.model.background.estimate_plate`).

    Args:
        data: the reference's frames and poses on the canvas.
        config: how the plate is estimated.

    Returns:
        [S, S, 3] uint8 RGB.
    """
    plate = estimate_plate(data.frames, data.joints, data.layout, data.usable, config)
    log.info("background plate from %d frames; %.1f%% of the canvas never free of the person (median of all "
             "frames there)", plate.frames, 100.0 * plate.fallback_share)
    return plate.image


@contextlib.contextmanager
def frame_store(count: int, size: int) -> Iterator[np.ndarray]:
    """A [count, size, size, 3] uint8 array: in memory when small, else a temporary memory-mapped file."""
    nbytes = count * size * size * 3
    if nbytes <= _IN_MEMORY_BYTES:
        yield np.zeros((count, size, size, 3), dtype=np.uint8)
        return
    from pose_io.atomic import check_free_space

    # A frame cache that does not fit would fill the shared disk and end in SIGBUS half-way through reading.
    check_free_space(Path(tempfile.gettempdir()), nbytes, f"a frame cache of {count} frames at {size}x{size}")
    with tempfile.TemporaryDirectory(prefix="clone2d-frames-") as tmp:
        log.info("keeping %d frames (%.1f GiB) in a memory-mapped file", count, nbytes / 2**30)
        arr = np.lib.format.open_memmap(os.path.join(tmp, "frames.npy"), mode="w+", dtype=np.uint8,
                                        shape=(count, size, size, 3))
        try:
            yield arr
        finally:
            del arr


def read_reference(
    poses_path: str | os.PathLike, frames_path: str | os.PathLike, align: str = "exact", layout: str = LAYOUT,
) -> tuple[PoseTrack, Frames, int]:
    """Open the reference's poses and frames and check that they belong together.

    Args:
        poses_path: any pose track ``pose_io`` reads.
        frames_path: a video or a folder of images.
        align: ``exact`` (counts must agree) or ``trim`` (use the common prefix).
        layout: the layout of the returned track (body15; body31 keeps the face, hands and feet the poses have).

    Returns:
        ``(track in ``layout`` with the frames' image size, frame stream, frame count to use)``.
    """
    from pose_io.readers import read_detections, track_from_detections
    from pose_io.video import read_frames

    if align not in ALIGN_MODES:
        raise InputError(f"unknown --align {align!r}; valid: {', '.join(ALIGN_MODES)}")
    frames = read_frames(frames_path)
    detections = read_detections(poses_path)
    if detections.image_size is not None and tuple(detections.image_size) != tuple(frames.size):
        raise InputError(
            f"{poses_path}: poses are for {detections.image_size[0]}x{detections.image_size[1]} frames, "
            f"{frames_path} has {frames.size[0]}x{frames.size[1]}"
        )
    track = track_from_detections(detections, fps=None, image_size=tuple(frames.size))
    if frames.kind == "video":
        track = track.replace(fps=frames.fps)
    track = track.to_layout(layout)
    n_frames, n_poses = frames.num_frames, track.num_frames
    if n_frames != n_poses:
        if align != "trim":
            raise InputError(
                f"{poses_path} has {n_poses} poses but {frames_path} has {n_frames} frames; "
                f"pass --align trim to use the first {min(n_frames, n_poses)} of each"
            )
        log.warning("using the first %d frames and poses (%d poses, %d frames)", min(n_frames, n_poses),
                    n_poses, n_frames)
    count = min(n_frames, n_poses)
    return track.frames(0, count), frames, count


def track_summary(track: PoseTrack, usable: np.ndarray) -> dict[str, Any]:
    """Plain-data summary of the reference's poses for the model file."""
    layout = track.joint_layout
    lengths = reference_limb_lengths(track.joints, layout)
    bones = {f"{a}-{b}": float(length) for (a, b), length in zip(layout.limbs, lengths)}
    return {
        "frames": track.num_frames,
        "usable_frames": int(usable.sum()),
        "skipped_frames": int((~usable).sum()),
        "fps": track.fps,
        "image_size": list(track.image_size),
        "layout": track.layout,
        "visible_fraction": (1.0 - track.missing.mean(axis=0)).astype(np.float32),
        "median_bone_lengths": bones,
    }


def reference_codes(
    track: PoseTrack, weights: str | os.PathLike | None
) -> tuple[dict[str, Any] | None, str | None, str | None]:
    """The retargeting network's codes of the reference: ``(codes dict, weights SHA-256, weights path)``.

    An explicitly given ``weights`` file must load and encode the track; without one, the shipped weights are
    used when present, and otherwise no codes are stored (training still works; drive then needs --weights
    for ``--method retarget``).
    """
    from retarget.api import PACKAGED_WEIGHTS, load_retargeter

    if weights is None and not PACKAGED_WEIGHTS.is_file():
        log.warning("no retargeting weights are shipped; storing no reference codes (pass --weights to store them)")
        return None, None, None
    path = Path(weights) if weights is not None else PACKAGED_WEIGHTS
    try:
        retargeter = load_retargeter(path, device="cpu")
        codes = retargeter.reference_codes(track)
    except InputError as exc:
        if weights is not None:
            raise
        log.warning("reference codes: %s; storing none", exc)
        return None, None, None
    # how the view code was pooled: `clone drive` recomputes codes pooled otherwise
    stored = {**codes.to_dict(), "view_pool": retargeter.config.view_pool}
    return stored, file_sha256(path), str(path.resolve())


def maybe_scale_stats(track: PoseTrack) -> ScaleStats | None:
    """The reference's global-scale statistics, or None (with a warning) when its poses do not give them."""
    try:
        return scale_stats(track.joints, track.joint_layout)
    except InputError as exc:
        log.warning("reference: %s; --method global-scale will not be available", exc)
        return None
