"""The settings of retargeting and the values it passes around: :class:`InferenceConfig`, a reference's
:class:`ReferenceCodes` and a driver's :class:`PreparedMotion` (the algorithm is :mod:`retarget.inference.algorithm`)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from pose_io.errors import InputError
from pose_io.limits import MAX_FPS, MIN_FPS
from retarget.inference.placement import Placement

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
VIEW_POOLS: tuple[str, ...] = ("facing", "nearest", "mean", "dominant")

@dataclass(frozen=True)
class InferenceConfig:
    """How tracks are cut for the network, and how much each driver window's motion code is refined.

    Attributes:
        window: frames per network pass for long tracks (a multiple of 8); memory is bounded by it.
        overlap: frames neighbouring passes share; outputs are cross-faded linearly over them.
        code_window: window length a reference's static codes are encoded over (the training length).
        code_stride: step between those windows.
        view_pool: how the reference's view code comes from its windows' codes
            (:func:`retarget.inference.algorithm.pool_view_codes`): ``facing``, the code of the window nearest
            the mean of the windows that face the way most do when the reference shows both her front and her
            back, of all windows otherwise (the default: a fashion video that turns her back for a fifth of its
            windows gave a side view with ``nearest``, the retargeted shoulders 0.18-0.39 of the torso apart
            against her own 0.59-0.65; ``facing`` 0.60-0.63, and the validation below unchanged to the last
            digit, its reference never turning); ``nearest``, the code of the window nearest their mean (the
            mean of two windows' codes when there are only two, which are equally near it); ``mean``, their
            mean; ``dominant``, nearest the mean of the half nearest their medoid (on validation +0.11 ± 0.04
            against ``nearest``). The skeleton code is always the mean: a body keeps its proportions,
            while a person who turns is seen from several views and the mean of their codes is no view's code.
            Chosen on validation (``nearest`` against ``mean``: world cases with 256-frame references, pose
            MSE x10³ 1.32 -> 1.09, paired -0.23 ± 0.06 over 200 cases; `clone retarget eval-cloning`, whose
            reference is 458 frames, 3.33 -> 3.19 %, -0.14 ± 0.05; 128-frame references +0.007 ± 0.008).
        batch: windows of ``window`` frames run through the network at once (``batch * window`` frames per
            pass; short clips of one length are stacked up to that many frames).
        refine_steps: Adam steps that refine each driver window's motion code before it is decoded
            (:mod:`retarget.inference.refine`, :mod:`retarget.inference.numpy_refine`). 0 = the encoder's code
            as it is (as the authors run their models).
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
    view_pool: str = "facing"

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
