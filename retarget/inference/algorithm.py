"""What retargeting does whatever runs the network: settings, reference codes, and the algorithm around the network.

:class:`RetargeterBase` prepares tracks (:mod:`retarget.inference.tracks`), cuts them into windows and stacks the
windows of many tracks (:mod:`retarget.inference.windows`), and integrates, smooths and places the result; a backend
(:mod:`retarget.api`: torch or numpy) only runs the network on numpy arrays.

The network runs at the frame rate it was trained at (``InferenceConfig.fps``): a track at another rate (25 fps
film, 60 fps phone video) is resampled to it first and the result back to the driver's own frames. Run as they
are, such drivers look slowed down or sped up to the network, and its root path and poses get worse (measured
on the validation split: README, "At the network's frame rate").
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from typing import Any

import numpy as np

from pose_io.clean import smooth_joints
from pose_io.errors import InputError
from pose_io.limits import check_frame_count
from pose_io.resample import resample, resampled_frames
from pose_io.track import PoseTrack
from retarget.inference.config import FPS_TOLERANCE, InferenceConfig, PreparedMotion, ReferenceCodes
from retarget.inference.placement import placement_of, placement_shift, shifted
from retarget.inference.tracks import canvas_scale, prepare
from retarget.inference.windows import pad_to_multiple, run_windowed, strided_starts
from retarget.network.config import min_frames
from retarget.network.preprocess import (
    LAYOUT,
    LOCAL_JOINTS,
    NUM_ROWS,
    NormStats,
    PreprocessConfig,
    channels_to_joints,
    joints_to_channels,
)

_min_frames = functools.lru_cache(maxsize=8)(min_frames)  # configs are frozen (hashable) dataclasses


# A window faces the camera (or shows its back) when its shoulders are this share of its torso's length apart.
FACING_WIDTH = 0.3


def window_facing(windows: np.ndarray, stats: NormStats) -> np.ndarray:
    """[N] +1 where a window [N, 30, L] of network input faces the camera, -1 where it shows its back, 0 between:
    the sign of its median shoulder width over its torso's length (the right shoulder on the image's left when
    facing it) beyond ``FACING_WIDTH``."""
    n, _, length = windows.shape
    rows = windows.reshape(n, NUM_ROWS, 2, length) * stats.std[None, :, :, None] + stats.mean[None, :, :, None]
    right, left, neck = (LOCAL_JOINTS.index(name) for name in ("r_shoulder", "l_shoulder", "neck"))
    torso = np.hypot(rows[:, neck, 0], rows[:, neck, 1])  # [N, L] the neck from the root (MidHip)
    with np.errstate(invalid="ignore", divide="ignore"):
        width = np.nanmedian((rows[:, left, 0] - rows[:, right, 0]) / torso, axis=1)  # [N]
    return np.where(width > FACING_WIDTH, 1, np.where(width < -FACING_WIDTH, -1, 0))


def pool_view_codes(codes: np.ndarray, pool: str, facing: np.ndarray | None = None) -> np.ndarray:
    """One view code [C] from a reference's window codes [N, C] (``InferenceConfig.view_pool``).

    ``mean``: their mean. ``nearest``: the window code nearest their mean. ``facing``: the same, over the windows
    that face the way most of them do when the reference shows both her front and her back (``facing`` [N], see
    :func:`window_facing`), over all of them otherwise: the mean of front and back codes is a side view's.
    ``dominant``: the window code nearest the mean of the half of the windows nearest their medoid.
    """
    codes = np.asarray(codes, dtype=np.float64)
    if pool == "mean":
        return codes.mean(axis=0).astype(np.float32)
    kept = codes
    if pool == "facing" and facing is not None and (facing > 0).any() and (facing < 0).any():
        side = 1 if (facing > 0).sum() >= (facing < 0).sum() else -1
        kept = codes[facing == side]
    elif pool == "dominant":
        dist = np.sqrt(((codes[:, None] - codes[None]) ** 2).sum(axis=-1))  # [N, N]
        medoid = int(np.argmin(dist.sum(axis=1)))
        kept = codes[np.argsort(dist[medoid], kind="stable")[: max(2, (len(codes) + 1) // 2)]]
    if len(kept) < 3:
        return kept.mean(axis=0).astype(np.float32)
    mean = kept.mean(axis=0)
    return kept[int(np.argmin(((kept - mean) ** 2).sum(axis=1)))].astype(np.float32)


class RetargeterBase:
    """What both backends do the same way; a backend supplies ``model`` and runs the network on numpy arrays.

    Subclasses are dataclasses with ``model``, ``stats`` (:class:`NormStats`), ``preprocess``
    (:class:`PreprocessConfig`) and ``config`` (:class:`InferenceConfig`).
    """

    model: Any
    stats: NormStats
    preprocess: PreprocessConfig
    config: InferenceConfig

    # -- what a backend provides --------------------------------------------------------------------------

    def _run(self, windows: np.ndarray, body: np.ndarray | None, view: np.ndarray | None) -> np.ndarray:
        """[N, 30, L] float32 -> [N, 30, L] float32 decoded with the codes ``body`` [Cb] and ``view`` [Cv]."""
        raise NotImplementedError

    def _encode_static(self, windows: np.ndarray, which: str) -> np.ndarray:
        """[N, 30, L] float32 -> [N, C] float32 skeleton (``which="body"``) or view codes."""
        raise NotImplementedError

    # -- shared --------------------------------------------------------------------------------------------

    @property
    def variant(self) -> str:
        return self.model.variant

    @property
    def min_frames(self) -> int:
        """Shortest track (frames at the network's rate, ``config.fps``) the network takes."""
        return _min_frames(self.model.config)  # the model's min_frames, worked out once per architecture

    def reference_codes(
        self,
        track: PoseTrack,
        view: PoseTrack | None = None,
        *,
        name: str = "reference track",
        view_name: str = "view track",
    ) -> ReferenceCodes:
        """Skeleton code, view code and placement of a reference person.

        Args:
            track: the reference (any layout convertible to body15); gives the skeleton, the placement,
                the pixel space of retargeted tracks and, unless ``view`` is given, the view.
            view: optional second track whose view code is used instead.
            name: how error messages call ``track`` (e.g. its file).
            view_name: how error messages call ``view``.

        Raises:
            InputError: see :meth:`retarget` for the conditions.
        """
        x, scale, body15 = self._prepare(track, name, self._network_rate(track, name))  # [30, T']
        config = self.model.config
        body = self._static_code(x, "body") if config.body_channels is not None else None
        view_code = None
        if config.view_channels is not None:
            if view is not None:
                x = self._prepare(view, view_name, self._network_rate(view, view_name))[0]
            view_code = self._static_code(x, "view")
        placement = placement_of(body15, name)
        return ReferenceCodes(body, view_code, placement, track.image_size, scale)

    def retarget(self, motion: PoseTrack, reference: ReferenceCodes, *, name: str = "motion track") -> PoseTrack:
        """The motion of ``motion`` performed by the reference person, in the reference's pixels.

        Args:
            motion: driver track, any layout convertible to body15, at least :attr:`min_frames` frames long at
                the network's rate (``config.fps``: a 60 fps track needs twice as many frames).
            reference: from :meth:`reference_codes` of a track with the same network.
            name: how error messages call ``motion`` (e.g. its file).

        Returns:
            body15 track with ``len(motion)`` frames, the driver's fps and the reference's image size;
            every joint present (confidence 1). Its size comes from the skeleton code; a network without
            a skeleton encoder keeps the driver's skeleton at the share of the frame height it had.

        Raises:
            InputError: too short a track, a layout that cannot give body15, no joints at all or a joint
                never detected, or reference codes from a different network.
        """
        self._check_reference(reference)
        return self.retarget_prepared([self.prepare_motion(motion, name)], reference)[0]

    def retarget_many(
        self, motions: Sequence[PoseTrack], reference: ReferenceCodes, names: Sequence[str] | None = None
    ) -> list[PoseTrack]:
        """:meth:`retarget` of many tracks, their windows stacked through the network together.

        Every track is checked (and prepared) before the network runs, so a bad one raises before any work.

        Args:
            motions: driver tracks.
            reference: as for :meth:`retarget`.
            names: how error messages call each track (default "motion track i").
        """
        self._check_reference(reference)
        names = list(names) if names is not None else [f"motion track {i}" for i in range(len(motions))]
        return self.retarget_prepared([self.prepare_motion(m, n) for m, n in zip(motions, names)], reference)

    def prepare_motion(self, motion: PoseTrack, name: str = "motion track") -> PreparedMotion:
        """The network input of a driver track (:meth:`retarget` raises what this raises)."""
        rate = self._network_rate(motion, name)
        return PreparedMotion(self._prepare(motion, name, rate)[0], float(motion.fps), name, len(motion), rate)

    def retarget_prepared(self, motions: Sequence[PreparedMotion], reference: ReferenceCodes) -> list[PoseTrack]:
        """Retarget prepared driver tracks (:meth:`prepare_motion`): windows of all of them go through the
        network together, ``config.batch * config.window`` frames at a time."""
        self._check_reference(reference)
        scale = self._reference_scale(reference)
        body, view = (None if c is None else np.asarray(c, np.float32) for c in (reference.body, reference.view))
        outputs = run_windowed(
            [m.x for m in motions], lambda windows: self._run(windows, body, view), self.model.config.downsampling,
            self.config.window, self.config.overlap, self.config.batch * self.config.window,
        )  # fmt: skip
        return [self._finish(y, m, reference, scale) for y, m in zip(outputs, motions)]

    def _network_rate(self, track: PoseTrack, name: str, target: float | None = None) -> float:
        """The frame rate ``track`` goes through the network at: ``target`` (default ``config.fps``), or its own
        within ``FPS_TOLERANCE`` of it (or with a target of 0).

        Raises:
            InputError: too few or too many frames at that rate.
        """
        fps = track.fps
        target = self.config.fps if target is None else target
        rate = fps if not target or abs(fps / target - 1) <= FPS_TOLERANCE else target
        if rate == fps:
            frames, what, at = len(track), f"{name}: {len(track)} frames", ""
        else:
            frames = resampled_frames(len(track), fps, rate)
            check_frame_count(frames, f"{name}: {len(track)} frames at {fps:g} fps, at the network's {rate:g} fps")
            what = f"{name}: {len(track)} frames at {fps:g} fps, {frames} at the network's {rate:g} fps"
            at = " at that rate"
        if frames < self.min_frames:
            raise InputError(f"{what}; the retargeting network needs at least {self.min_frames}{at}")
        return rate

    def _finish(self, y: np.ndarray, motion: PreparedMotion, reference: ReferenceCodes, scale: float) -> PoseTrack:
        """[30, T'] network output -> body15 track in the reference's pixels, with the driver's fps and frames."""
        fps, rate = motion.fps, motion.rate
        # [T, 15, 2] canvas, worked out in float64 (y's values converted as they are read), time-major
        joints = channels_to_joints(y[None], self.stats, dtype=np.float64)[0]
        joints /= scale  # reference pixels
        smooth_joints(joints, self.preprocess.output_sigma, out=joints)  # in place, block by block
        # place(), its float64 sums rounded straight into the float32 joints of the track. They go where y lies
        # when it is [T, 30] float32 memory (run_windowed's, this track's alone, read above): a long track's
        # new array would cost fresh pages on every call (~0.5 ms of 31 at 10,000 frames, numpy backend).
        rows = y.T  # [T, 30]
        into = rows.reshape(joints.shape) if rows.dtype == np.float32 and rows.flags.c_contiguous else None
        placed = shifted(joints, placement_shift(joints, reference.placement),
                         np.empty(joints.shape, np.float32) if into is None else into)  # fmt: skip
        track = PoseTrack.complete(placed, rate, reference.image_size, LAYOUT.name, copy=False)  # = body15_track
        if rate == fps and len(track) == motion.frames:
            return track
        return resample(track, fps, frames=motion.frames)

    def _static_code(self, x: np.ndarray, which: str) -> np.ndarray:
        """[30, T] -> [C] code over windows of ``code_window`` frames: their mean, or for the view code of three
        windows or more as ``config.view_pool`` says (:func:`pool_view_codes`)."""
        length, window = x.shape[-1], self.config.code_window
        if length < window:
            windows = pad_to_multiple(x, 8)[0][None]  # [1, 30, T8]
        else:
            starts = strided_starts(length, window, self.config.code_stride)
            windows = np.stack([x[:, s : s + window] for s in starts])  # [N, 30, window]
        batch = self.config.batch
        codes = np.concatenate([self._encode_static(windows[i : i + batch], which)
                                for i in range(0, len(windows), batch)])  # fmt: skip  # [N, C]
        if which == "view" and len(codes) >= 3:
            return pool_view_codes(codes, self.config.view_pool, window_facing(windows, self.stats))
        return codes.mean(axis=0).astype(np.float32)

    def _reference_scale(self, reference: ReferenceCodes) -> float:
        if reference.scale is not None:
            return reference.scale
        if self.preprocess.body_height > 0:
            raise InputError(
                "reference codes: written by an older clone2d without the reference's scale; recompute them"
                " (run `clone train-ref` again)"
            )
        return canvas_scale(reference.image_size, self.preprocess)

    def _check_reference(self, reference: ReferenceCodes) -> None:
        for name, code, dim in (
            ("skeleton", reference.body, self.model.config.body_dim),
            ("view", reference.view, self.model.config.view_dim),
        ):
            size = 0 if code is None else int(np.asarray(code).size)
            if size != dim:
                raise InputError(
                    f"reference codes: {name} code of size {size}, this {self.variant} network uses {dim};"
                    " they come from a different retargeting model"
                )

    def _prepare(
        self, track: PoseTrack, name: str, rate: float | None = None
    ) -> tuple[np.ndarray, float, np.ndarray]:
        """The network input [30, T'] float32 of a real track at ``rate`` (from :meth:`_network_rate`; None =
        its own), the scale to the canvas and its body15 joints [T, 15, 2] in its own pixels and frames
        (:class:`retarget.inference.tracks.PreparedTrack`'s, whose canvas becomes x)."""
        if rate is None:
            rate = self._network_rate(track, name, target=0.0)  # its own rate, its length checked
        prepared = prepare(track, self.preprocess, name, fps=rate)
        # [30, T] float32, a view of [T, 30] (worked out in the canvas' memory, nothing else uses it), kept
        # time-major: windows are cut and run that way (retarget.inference.windows)
        x = joints_to_channels(prepared.canvas[None], self.stats, overwrite=True, dtype=np.float32)[0]
        return x, prepared.scale, prepared.body15
