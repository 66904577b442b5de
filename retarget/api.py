"""Retargeting a pose track onto a reference person: the library entry point.

    retargeter = load_retargeter("weights.pt")
    reference = retargeter.reference_codes(reference_track)       # skeleton + view + where they stand
    moved = retargeter.retarget(driver_track, reference)          # body15, in the reference's pixels
    many = retargeter.retarget_many(driver_tracks, reference)     # many clips batched through the network

The reference's codes summarise its whole track (the mean of the codes of overlapping windows as long as
the training windows). The output keeps the driver's frame count and fps; its size comes from the
skeleton code, its root trajectory is integrated from the predicted velocity, centred where the reference
stands and with the feet on the reference's ground line.

Each driver window's motion code is refined with a few gradient steps before it is decoded
(``InferenceConfig.refine_steps``), which keeps the driver's range of motion. Both backends do it, with the same
results up to float32 rounding: torch (:class:`Retargeter`, any device; :mod:`retarget.inference.refine`) and numpy
(:class:`NumpyRetargeter`, CPU, never imports torch, weights from :mod:`retarget.network.numpy_weights`; the
decoder's gradient written out, :mod:`retarget.inference.numpy_refine`), the default on a CPU. Everything around
the network (preparing tracks, windows, placing the result) is the same numpy code for both.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from pose_io.errors import InputError
from pose_io.track import PoseTrack
from retarget.inference.algorithm import RetargeterBase
from retarget.inference.config import InferenceConfig, PreparedMotion, ReferenceCodes
from retarget.network.packaged import PACKAGED_WEIGHTS
from retarget.network.preprocess import NormStats, PreprocessConfig

if TYPE_CHECKING:
    import torch

    from retarget.network.model import RetargetNet
    from retarget.network.numpy_net import NumpyRetargetNet

log = logging.getLogger(__name__)

# "auto": numpy on the CPU when the weights have an up-to-date export, else torch.
BACKENDS = ("auto", "numpy", "torch")

__all__ = [
    "BACKENDS", "PACKAGED_WEIGHTS", "InferenceConfig", "NumpyRetargeter", "PreparedMotion", "ReferenceCodes",
    "Retargeter", "RetargeterBase", "load_retargeter",
]


@dataclass(eq=False)
class Retargeter(RetargeterBase):
    """A loaded retargeting network with its statistics, ready for inference (torch, any device).

    Attributes:
        model: the network (eval mode, on ``device``).
        stats: its input statistics.
        preprocess: canvas height and smoothing.
        device: where it runs.
        config: windowing of long tracks and motion-code refinement.
    """

    model: RetargetNet
    stats: NormStats
    preprocess: PreprocessConfig
    device: torch.device
    config: InferenceConfig = field(default_factory=InferenceConfig)

    def _run(self, windows: np.ndarray, body: np.ndarray | None, view: np.ndarray | None) -> np.ndarray:
        import torch

        from retarget.inference.refine import decode_refined

        c = self.config
        # windows arrive as views of time-major memory (retarget.inference.windows); torch gets the contiguous
        # [N, 30, L] it always had, so its kernels, and their results, are the same
        x = torch.from_numpy(np.ascontiguousarray(windows)).to(self.device)  # [N, 30, L]
        if c.refine_steps == 0:
            with torch.inference_mode():
                y = self.model.decode(self.model.encode_motion(x), self._code_tensor(body), self._code_tensor(view))
        else:
            y = decode_refined(self.model, x, self._code_tensor(body), self._code_tensor(view), c.refine_steps,
                               c.refine_rate, c.refine_anchor, c.code_window, c.code_stride)  # fmt: skip
        return y.float().cpu().numpy()

    def _encode_static(self, windows: np.ndarray, which: str) -> np.ndarray:
        import torch

        encode = self.model.encode_body if which == "body" else self.model.encode_view
        with torch.inference_mode():
            x = torch.from_numpy(np.ascontiguousarray(windows)).to(self.device)  # [N, 30, L]
            return encode(x)[:, :, 0].float().cpu().numpy()  # [N, C]

    def _input(self, track: PoseTrack, name: str, rate: float | None = None) -> torch.Tensor:
        """[1, 30, T'] float32 normalised network input of a real track at ``rate`` (:meth:`_network_rate`;
        None: its own), on ``device``."""
        import torch

        x = self._prepare(track, name, rate)[0]
        return torch.from_numpy(np.ascontiguousarray(x))[None].to(self.device)

    def _code_tensor(self, code: np.ndarray | None) -> torch.Tensor | None:
        import torch

        if code is None:
            return None
        return torch.as_tensor(np.asarray(code, dtype=np.float32), device=self.device)[None, :, None]  # [1, C, 1]


@dataclass(eq=False)
class NumpyRetargeter(RetargeterBase):
    """:class:`Retargeter` evaluated by numpy on the CPU, motion-code refinement included; never imports torch. Its
    results are a :class:`Retargeter`'s with the same config, up to float32 rounding.

    Its matrix products run on numpy's BLAS, whose thread count the process owns: on a machine another job
    keeps busy, :func:`retarget.network.blas.set_blas_threads` to the free cores (``clone`` does) is many times faster.

    Attributes:
        model: the network (:class:`retarget.network.numpy_net.NumpyRetargetNet`).
        stats: its input statistics.
        preprocess: canvas height and smoothing.
        config: windowing of long tracks and motion-code refinement.
    """

    model: NumpyRetargetNet
    stats: NormStats
    preprocess: PreprocessConfig
    config: InferenceConfig = field(default_factory=InferenceConfig)

    def _run(self, windows: np.ndarray, body: np.ndarray | None, view: np.ndarray | None) -> np.ndarray:
        c = self.config
        if c.refine_steps == 0:
            return self.model.run(windows, body, view)
        from retarget.inference.numpy_refine import decode_refined

        return decode_refined(self.model, np.ascontiguousarray(windows), body, view, c.refine_steps, c.refine_rate,
                              c.refine_anchor, c.code_window, c.code_stride)  # fmt: skip

    def _encode_static(self, windows: np.ndarray, which: str) -> np.ndarray:
        encode = self.model.encode_body if which == "body" else self.model.encode_view
        return encode(windows)[:, :, 0]


def _pad_to_multiple(x: torch.Tensor, multiple: int) -> tuple[torch.Tensor, int]:
    """Reflect-pad a tensor [B, C, T] on both ends to a multiple of ``multiple``; returns (padded, left pad)."""
    import torch.nn.functional as F

    extra = -x.shape[-1] % multiple
    left = extra // 2
    if extra == 0:
        return x, 0
    return F.pad(x, (left, extra - left), mode="reflect"), left


def load_retargeter(
    weights: str | Path | None = None,
    device: str = "cpu",
    config: InferenceConfig | None = None,
    backend: str = "torch",
) -> Retargeter | NumpyRetargeter:
    """Load a retargeting network for inference.

    Args:
        weights: a clone2d checkpoint, one of the authors' ``pretrained_*.pth`` with its ``meanpose*.npy`` /
            ``stdpose*.npy`` next to it, or a numpy export (``.npz``, :mod:`retarget.network.numpy_weights`); None = the
            weights shipped in the package.
        device: "auto", "cpu", "cuda" or "cuda:N" (the numpy backend runs on the CPU: "auto" or "cpu").
        config: windowing of long tracks and motion-code refinement (default :class:`InferenceConfig`).
        backend: "torch" (:class:`Retargeter`); "numpy" (:class:`NumpyRetargeter`, needs an up-to-date export
            beside the checkpoint, or an ``.npz`` as ``weights``); "auto": numpy when the device allows it and
            such an export exists, else torch.

    Raises:
        InputError: no packaged weights yet, a missing/corrupt/foreign file, an unusable device, or a backend
            that cannot run these weights on that device.
    """
    if backend not in BACKENDS:
        raise InputError(f"unknown backend {backend!r}; valid: {', '.join(BACKENDS)}")
    if weights is None:
        if not PACKAGED_WEIGHTS.is_file():
            raise InputError(
                f"no trained retargeting weights are shipped yet ({PACKAGED_WEIGHTS.name}); pass a checkpoint"
                " from `clone retarget train` or the authors' pretrained_full.pth with --weights"
            )
        weights = PACKAGED_WEIGHTS
    weights = Path(weights)
    on_cpu = device.strip().lower() in ("auto", "cpu")
    is_export = weights.suffix.lower() == ".npz"
    config = config or InferenceConfig()
    if backend != "torch" and on_cpu:
        from retarget.network.numpy_weights import current_export, read_npz

        export = read_npz(weights) if is_export else current_export(weights)
        if export is not None:
            log.info("retargeting with the %s network from %s with numpy on the CPU (motion codes refined by %d "
                     "steps)", export.variant, export.path, config.refine_steps)  # fmt: skip
            return NumpyRetargeter(export.model, export.stats, export.preprocess, config)
        if backend == "numpy":
            raise InputError(
                f"{weights}: no up-to-date numpy export beside it; write one with `python -m retarget.network.numpy_weights"
                f" {weights} --out FILE.npz` and pass that file"
            )
    if backend == "numpy":
        raise InputError(f"the numpy backend runs on the CPU, not on device {device!r}")
    if is_export:
        raise InputError(f"{weights}: a numpy export runs on the CPU with the numpy backend; pass its checkpoint")
    from retarget.network.checkpoint import load_weights
    from retarget.runtime import resolve_device

    try:
        dev = resolve_device(device)
    except ValueError as exc:
        raise InputError(str(exc)) from None
    loaded = load_weights(weights)
    log.info("retargeting with the %s network from %s on %s", loaded.variant, loaded.path, dev)
    return Retargeter(loaded.model.to(dev).eval(), loaded.stats, loaded.preprocess, dev, config)
