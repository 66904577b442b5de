"""What retargeting does whatever runs the network: settings, reference codes, and the algorithm around the network.

:class:`RetargeterBase` prepares tracks (:mod:`retarget.tracks`), cuts them into windows and stacks the
windows of many tracks (:mod:`retarget.windows`), and integrates, smooths and places the result; a backend
(:mod:`retarget.api`: torch or numpy) only runs the network on numpy arrays.

The network runs at the frame rate it was trained at (``InferenceConfig.fps``): a track at another rate (25 fps
film, 60 fps phone video) is resampled to it first and the result back to the driver's own frames. Run as they
are, such drivers look slowed down or sped up to the network, and its root path and poses get worse (measured
on the validation split: README, "At the network's frame rate").
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from pose_io.clean import smooth_joints
from pose_io.errors import InputError
from pose_io.limits import MAX_FPS, MIN_FPS, check_frame_count
from pose_io.resample import resample, resampled_frames
from pose_io.track import PoseTrack
from retarget.network_config import min_frames
from retarget.placement import Placement, placement_of, placement_shift, shifted
from retarget.preprocess import LAYOUT, NormStats, PreprocessConfig, channels_to_joints, joints_to_channels
from retarget.tracks import canvas_scale, prepare
from retarget.windows import pad_to_multiple, run_windowed, strided_starts

# Refinement of the driver's motion code, chosen on the validation split (README, "Motion-code refinement").
REFINE_STEPS = 30
REFINE_RATE = 0.02
REFINE_ANCHOR = 0.3
# The motion world's frame rate, which every clone2d network was trained at (the authors' trained on Mixamo clips,
# which Mixamo exports at 30 fps by default; their README states no rate).
NETWORK_FPS = 30.0
# Tracks within 1 % of it (29.97 fps video) run as they are: the training's time warps span 0.7-1.4x.
FPS_TOLERANCE = 0.01

# How a reference's view code pools its windows (InferenceConfig.view_pool).
VIEW_POOLS: tuple[str, ...] = ("nearest", "mean")

_min_frames = functools.lru_cache(maxsize=8)(min_frames)  # configs are frozen (hashable) dataclasses


@dataclass(frozen=True)
class InferenceConfig:
    """How tracks are cut for the network, and how much each driver window's motion code is refined.

    Attributes:
        window: frames per network pass for long tracks (a multiple of 8); memory is bounded by it.
        overlap: frames neighbouring passes share; outputs are cross-faded linearly over them.
        code_window: window length a reference's static codes are encoded over (the training length).
        code_stride: step between those windows.
        view_pool: how the reference's view code comes from its windows' codes: ``nearest``, the code of the
            window nearest their mean (the mean of two windows' codes when there are only two, which are equally
            near it); ``mean``, their mean. The skeleton code is always the mean: a body keeps its proportions,
            while a person who turns is seen from several views and the mean of their codes is no view's code.
            Chosen on validation (``nearest`` against ``mean``: world cases with 256-frame references, pose
            MSE x10³ 1.32 -> 1.09, paired -0.23 ± 0.06 over 200 cases; `clone retarget eval-cloning`, whose
            reference is 458 frames, 3.33 -> 3.19 %, -0.14 ± 0.05; 128-frame references +0.007 ± 0.008).
        batch: windows of ``window`` frames run through the network at once (``batch * window`` frames per
            pass; short clips of one length are stacked up to that many frames).
        refine_steps: Adam steps that refine each driver window's motion code before it is decoded
            (:mod:`retarget.refine`; torch backend only). 0 = the encoder's code as it is (the numpy
            backend, the authors' models).
        refine_rate: their learning rate.
        refine_anchor: weight of the pull towards the encoder's code.
        fps: frame rate the network runs at: drivers and references more than ``FPS_TOLERANCE`` off it are
            resampled to it, and results back to the driver's frames (0 = every track at its own rate).
    """

    window: int = 1024
    overlap: int = 64
    code_window: int = 64
    code_stride: int = 32
    batch: int = 2
    refine_steps: int = REFINE_STEPS
    refine_rate: float = REFINE_RATE
    refine_anchor: float = REFINE_ANCHOR
    fps: float = NETWORK_FPS
    view_pool: str = "nearest"

    def __post_init__(self) -> None:
        if self.window % 8 or self.code_window % 8:
            raise ValueError("window and code_window must be multiples of 8")
        if not 0 <= self.overlap < self.window:
            raise ValueError("overlap must be in [0, window)")
        if self.code_stride <= 0 or self.batch <= 0:
            raise ValueError("code_stride and batch must be positive")
        if not isinstance(self.refine_steps, int) or self.refine_steps < 0:
            raise ValueError(f"refine_steps must be an integer >= 0, got {self.refine_steps!r}")
        if not (math.isfinite(self.refine_rate) and self.refine_rate > 0):
            raise ValueError(f"refine_rate must be finite and > 0, got {self.refine_rate!r}")
        if not (math.isfinite(self.refine_anchor) and self.refine_anchor >= 0):
            raise ValueError(f"refine_anchor must be finite and >= 0, got {self.refine_anchor!r}")
        if not (self.fps == 0 or MIN_FPS <= self.fps <= MAX_FPS):  # NaN fails both
            raise ValueError(f"fps must be 0 or from {MIN_FPS:g} to {MAX_FPS:g}, got {self.fps!r}")
        if self.view_pool not in VIEW_POOLS:
            raise ValueError(f"view_pool must be one of {', '.join(VIEW_POOLS)}, got {self.view_pool!r}")


@dataclass(frozen=True, eq=False)
class ReferenceCodes:
    """What retargeting needs to know about a reference person.

    Attributes:
        body: [Cb] float32 skeleton code, or None for a network without a skeleton encoder.
        view: [Cv] float32 view code, or None for a network without a view encoder.
        placement: median pose height, root x and ground line, in the reference's pixels.
        image_size: (width, height) of the reference's frames.
        scale: factor from the reference's pixels to the network canvas (None in files written before it
            was stored: then the image-height rule).
    """

    body: np.ndarray | None
    view: np.ndarray | None
    placement: Placement
    image_size: tuple[int, int]
    scale: float | None = None

    def to_dict(self) -> dict[str, np.ndarray]:
        """Plain arrays (float32 codes, float64 placement, int64 size) for storing in other files."""
        out = {
            "placement": np.array(
                [self.placement.height, self.placement.root_x, self.placement.ground_y], dtype=np.float64
            ),
            "image_size": np.array(self.image_size, dtype=np.int64),
        }
        if self.scale is not None:
            out["scale"] = np.array(self.scale, dtype=np.float64)
        for name, code in (("body", self.body), ("view", self.view)):
            if code is not None:
                out[name] = np.asarray(code, dtype=np.float32).copy()
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> ReferenceCodes:
        """Inverse of :meth:`to_dict` (values may be numpy arrays, tensors or lists).

        Raises:
            InputError: missing or malformed entries.
        """
        try:
            placement = np.asarray(data["placement"], dtype=np.float64).reshape(3)
            size = np.asarray(data["image_size"]).reshape(2)
            codes = {
                k: np.asarray(data[k], dtype=np.float32).reshape(-1) if data.get(k) is not None else None
                for k in ("body", "view")
            }
            scale = float(np.asarray(data["scale"]).reshape(())) if data.get("scale") is not None else None
        except (KeyError, ValueError, TypeError) as exc:
            raise InputError(f"reference codes: missing or malformed entry ({exc})") from None
        if not np.isfinite(placement).all() or (size <= 0).any():
            raise InputError("reference codes: invalid placement or image size")
        if scale is not None and not (np.isfinite(scale) and scale > 0):
            raise InputError("reference codes: invalid canvas scale")
        return cls(
            codes["body"], codes["view"], Placement(*map(float, placement)), (int(size[0]), int(size[1])), scale
        )


@dataclass(frozen=True, eq=False)
class PreparedMotion:
    """A driver track reduced to what retargeting it needs (:meth:`RetargeterBase.prepare_motion`).

    Attributes:
        x: [30, T'] float32 normalised network input, at the network's frame rate.
        fps: the driver's frame rate (the output keeps it).
        name: how messages call it.
        frames: the driver's frame count T (the output keeps it).
        rate: the frame rate of ``x`` (the network's, or the driver's own: :meth:`RetargeterBase._network_rate`).
    """

    x: np.ndarray
    fps: float
    name: str
    frames: int
    rate: float

    def __len__(self) -> int:
        """Frames of ``x`` (at ``rate``; what the network runs on)."""
        return int(self.x.shape[-1])


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
        """[30, T] -> [C] code over windows of ``code_window`` frames: their mean, or for the view code with
        ``view_pool="nearest"`` and three windows or more the window code nearest that mean."""
        length, window = x.shape[-1], self.config.code_window
        if length < window:
            windows = pad_to_multiple(x, 8)[0][None]  # [1, 30, T8]
        else:
            starts = strided_starts(length, window, self.config.code_stride)
            windows = np.stack([x[:, s : s + window] for s in starts])  # [N, 30, window]
        batch = self.config.batch
        codes = np.concatenate([self._encode_static(windows[i : i + batch], which)
                                for i in range(0, len(windows), batch)])  # fmt: skip  # [N, C]
        mean = codes.mean(axis=0)
        if which == "view" and self.config.view_pool == "nearest" and len(codes) >= 3:
            return codes[int(np.argmin(((codes - mean) ** 2).sum(axis=1)))].astype(np.float32)
        return mean.astype(np.float32)

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
        (:class:`retarget.tracks.PreparedTrack`'s, whose canvas becomes x)."""
        if rate is None:
            rate = self._network_rate(track, name, target=0.0)  # its own rate, its length checked
        prepared = prepare(track, self.preprocess, name, fps=rate)
        # [30, T] float32, a view of [T, 30] (worked out in the canvas' memory, nothing else uses it), kept
        # time-major: windows are cut and run that way (retarget.windows)
        x = joints_to_channels(prepared.canvas[None], self.stats, overwrite=True, dtype=np.float32)[0]
        return x, prepared.scale, prepared.body15
