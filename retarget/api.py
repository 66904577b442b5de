"""Retargeting a pose track onto a reference person: the library entry point.

    retargeter = load_retargeter("weights.pt")
    reference = retargeter.reference_codes(reference_track)       # skeleton + view + where they stand
    moved = retargeter.retarget(driver_track, reference)          # body15, in the reference's pixels

The reference's codes summarise its whole track (the mean of the codes of overlapping windows as long as
the training windows). The output keeps the driver's frame count and fps; its size comes from the
skeleton code, its root trajectory is integrated from the predicted velocity, centred where the reference
stands and with the feet on the reference's ground line.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch
import torch.nn.functional as F

from pose_io.clean import smooth_joints
from pose_io.errors import InputError
from pose_io.track import PoseTrack
from retarget.checkpoint import RetargetWeights, load_weights
from retarget.model import RetargetNet
from retarget.preprocess import (
    NormStats,
    Placement,
    PreparedTrack,
    PreprocessConfig,
    body15_track,
    canvas_scale,
    channels_to_joints,
    joints_to_channels,
    place,
    placement_of,
    prepare,
)
from retarget.runtime import resolve_device

log = logging.getLogger(__name__)

# The weights shipped with the package (trained by `clone retarget train`).
PACKAGED_WEIGHTS = Path(__file__).resolve().parent / "weights" / "clone2d_full.pt"


@dataclass(frozen=True)
class InferenceConfig:
    """How tracks are cut for the network.

    Attributes:
        window: frames per network pass for long tracks (a multiple of 8); memory is bounded by it.
        overlap: frames neighbouring passes share; outputs are cross-faded linearly over them.
        code_window: window length the reference's static codes are averaged over (the training length).
        code_stride: step between those windows.
        batch: windows run through the network at once.
    """

    window: int = 256
    overlap: int = 64
    code_window: int = 64
    code_stride: int = 32
    batch: int = 8

    def __post_init__(self) -> None:
        if self.window % 8 or self.code_window % 8:
            raise ValueError("window and code_window must be multiples of 8")
        if not 0 <= self.overlap < self.window:
            raise ValueError("overlap must be in [0, window)")
        if self.code_stride <= 0 or self.batch <= 0:
            raise ValueError("code_stride and batch must be positive")


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


@dataclass(eq=False)
class Retargeter:
    """A loaded retargeting network with its statistics, ready for inference.

    Attributes:
        model: the network (eval mode, on ``device``).
        stats: its input statistics.
        preprocess: canvas height and smoothing.
        device: where it runs.
        config: windowing of long tracks.
    """

    model: RetargetNet
    stats: NormStats
    preprocess: PreprocessConfig
    device: torch.device
    config: InferenceConfig = field(default_factory=InferenceConfig)

    @property
    def variant(self) -> str:
        return self.model.variant

    @property
    def min_frames(self) -> int:
        """Shortest track (frames) the network takes."""
        return self.model.min_frames

    # -- codes of a reference ----------------------------------------------------------------------------

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
        x, prepared = self._prepare(track, name)
        body = self._static_code(x, "body") if self.model.body_encoder is not None else None
        view_code = None
        if self.model.view_encoder is not None:
            view_code = self._static_code(x if view is None else self._input(view, view_name), "view")
        placement = placement_of(prepared.body15, name)
        return ReferenceCodes(body, view_code, placement, track.image_size, prepared.scale)

    @torch.inference_mode()
    def _static_code(self, x: torch.Tensor, which: str) -> np.ndarray:
        """[1, 30, T] -> [C] mean code over windows of ``code_window`` frames."""
        encode = self.model.encode_body if which == "body" else self.model.encode_view
        length = x.shape[-1]
        window = self.config.code_window
        if length < window:
            windows = _pad_to_multiple(x, 8)[0]  # [1, 30, T8]
        else:
            starts = list(range(0, length - window + 1, self.config.code_stride))
            if starts[-1] != length - window:
                starts.append(length - window)
            windows = torch.cat([x[:, :, s : s + window] for s in starts])  # [N, 30, window]
        codes = torch.cat([encode(chunk) for chunk in windows.split(self.config.batch)])  # [N, C, 1]
        return codes.mean(dim=0)[:, 0].cpu().numpy().astype(np.float32)

    # -- retargeting -------------------------------------------------------------------------------------

    def retarget(self, motion: PoseTrack, reference: ReferenceCodes, *, name: str = "motion track") -> PoseTrack:
        """The motion of ``motion`` performed by the reference person, in the reference's pixels.

        Args:
            motion: driver track, any layout convertible to body15, any length >= :attr:`min_frames`.
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
        x = self._input(motion, name)
        y = self._decode_track(x, reference)  # [1, 30, T]
        joints = channels_to_joints(y.double().cpu(), self.stats)[0].numpy()  # [T, 15, 2] canvas
        joints = joints / self._reference_scale(reference)  # reference pixels
        joints = place(smooth_joints(joints, self.preprocess.output_sigma), reference.placement)
        return body15_track(joints, motion.fps, reference.image_size)

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

    def _input(self, track: PoseTrack, name: str) -> torch.Tensor:
        """[1, 30, T] normalised network input of a real track."""
        return self._prepare(track, name)[0]

    def _prepare(self, track: PoseTrack, name: str) -> tuple[torch.Tensor, PreparedTrack]:
        """The network input [1, 30, T] of a real track, and the track as prepared for it."""
        if len(track) < self.min_frames:
            raise InputError(
                f"{name}: {len(track)} frames; the retargeting network needs at least {self.min_frames}"
            )
        prepared = prepare(track, self.preprocess, name)
        x = joints_to_channels(torch.from_numpy(prepared.canvas)[None], self.stats)  # [1, 30, T]
        return x.to(self.device, torch.float32), prepared

    @torch.inference_mode()
    def _decode_track(self, x: torch.Tensor, reference: ReferenceCodes) -> torch.Tensor:
        """Self-contained windows through the network, cross-faded: [1, 30, T] -> [1, 30, T]."""
        length = x.shape[-1]
        padded, left = _pad_to_multiple(x, self.model.config.downsampling)  # [1, 30, T8]
        body = self._code_tensor(reference.body)
        view = self._code_tensor(reference.view)
        total = padded.shape[-1]
        window, overlap = self.config.window, self.config.overlap
        if total <= window:
            out = self.model.decode(self.model.encode_motion(padded), body, view)
            return out[:, :, left : left + length]
        starts = list(range(0, total - window, window - overlap)) + [total - window]
        ramp = torch.ones(window, device=x.device)
        if overlap:
            edge = (torch.arange(overlap, device=x.device, dtype=torch.float32) + 0.5) / overlap
            ramp[:overlap] = edge
            ramp[-overlap:] = edge.flip(0)
        acc = torch.zeros_like(padded)  # [1, 30, T8]
        weight = torch.zeros(total, device=x.device)
        for i in range(0, len(starts), self.config.batch):
            chunk = starts[i : i + self.config.batch]
            windows = torch.cat([padded[:, :, s : s + window] for s in chunk])  # [N, 30, W]
            out = self.model.decode(self.model.encode_motion(windows), body, view)  # [N, 30, W]
            for s, o in zip(chunk, out):
                w = ramp.clone()
                if s == 0:
                    w[:overlap] = 1.0  # nothing to fade with before the first window
                if s == total - window:
                    w[window - overlap :] = 1.0
                acc[0, :, s : s + window] += o * w
                weight[s : s + window] += w
        return (acc / weight)[:, :, left : left + length]

    def _code_tensor(self, code: np.ndarray | None) -> torch.Tensor | None:
        if code is None:
            return None
        return torch.as_tensor(np.asarray(code, dtype=np.float32), device=self.device)[None, :, None]  # [1, C, 1]


def _pad_to_multiple(x: torch.Tensor, multiple: int) -> tuple[torch.Tensor, int]:
    """Reflect-pad [B, C, T] on both ends to a multiple of ``multiple``; returns (padded, left pad)."""
    extra = -x.shape[-1] % multiple
    left = extra // 2
    if extra == 0:
        return x, 0
    return F.pad(x, (left, extra - left), mode="reflect"), left


def load_retargeter(
    weights: str | Path | None = None, device: str = "cpu", config: InferenceConfig = InferenceConfig()
) -> Retargeter:
    """Load a retargeting network for inference.

    Args:
        weights: a clone2d checkpoint, or one of the authors' ``pretrained_*.pth`` with its
            ``meanpose*.npy`` / ``stdpose*.npy`` next to it; None = the weights shipped in the package.
        device: "auto", "cpu", "cuda" or "cuda:N".
        config: windowing of long tracks.

    Raises:
        InputError: no packaged weights yet, a missing/corrupt/foreign file, or an unusable device.
    """
    if weights is None:
        if not PACKAGED_WEIGHTS.is_file():
            raise InputError(
                f"no trained retargeting weights are shipped yet ({PACKAGED_WEIGHTS.name}); pass a checkpoint"
                " from `clone retarget train` or the authors' pretrained_full.pth with --weights"
            )
        weights = PACKAGED_WEIGHTS
    try:
        dev = resolve_device(device)
    except ValueError as exc:
        raise InputError(str(exc)) from None
    loaded: RetargetWeights = load_weights(weights)
    log.info("retargeting with the %s network from %s on %s", loaded.variant, loaded.path, dev)
    return Retargeter(loaded.model.to(dev).eval(), loaded.stats, loaded.preprocess, dev, config)
