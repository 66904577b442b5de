"""The generator on ONNX Runtime, for `clone drive` on a CPU (optional extra ``fast``: onnxruntime + onnx).

On a CPU, batch 1, ONNX Runtime ran the U-Net generator at 256² 1.5-1.8x faster than eager torch under
inference mode, with outputs equal to 1e-6 (README, "Speed and memory"). The network is exported in
memory when driving starts (about a second); nothing is written to disk. Runtime ``int8`` runs a statically
quantised copy of the same export (:mod:`clone.runtime.int8`; about 2x the fp32 session, SSIM 0.003 lower
on the demo), cached on disk. Without the extra, or on a GPU, :func:`generator_runtime` picks torch.
"""

from __future__ import annotations

import importlib.util
import io
import logging
import warnings

import numpy as np
import torch
from torch import Tensor, nn

log = logging.getLogger(__name__)

RUNTIMES = ("auto", "torch", "onnx", "int8")
ONNX_RUNTIMES = ("onnx", "int8")  # the runtimes that need the extra and a CPU


def onnx_available() -> bool:
    """Whether onnxruntime and onnx (for the export) are installed."""
    return all(importlib.util.find_spec(m) is not None for m in ("onnxruntime", "onnx"))


def generator_runtime(runtime: str, device: torch.device) -> str:
    """The runtime to use: ``torch``, ``onnx`` or ``int8``.

    Args:
        runtime: ``auto`` (int8 ONNX Runtime on a CPU when installed, else torch), ``torch``, ``onnx`` (fp32
            ONNX Runtime) or ``int8`` (statically quantised ONNX Runtime, :mod:`clone.runtime.int8`).
        device: where the generator would run.

    Raises:
        ValueError: an unknown name, or ``onnx`` / ``int8`` on a GPU or without the extra.
    """
    if runtime not in RUNTIMES:
        raise ValueError(f"unknown generator runtime {runtime!r}; valid: {', '.join(RUNTIMES)}")
    if runtime == "auto":
        # int8: about 2x the fp32 session for 0.0025-0.003 SSIM on the demo's held-out pairs (README).
        return "int8" if device.type == "cpu" and onnx_available() else "torch"
    if runtime in ONNX_RUNTIMES and device.type != "cpu":
        raise ValueError(f"the {runtime} runtime runs on the CPU, not {device}")
    if runtime in ONNX_RUNTIMES and not onnx_available():
        raise ValueError(f"the {runtime} runtime needs the optional extra: pip install 'clone2d[fast]'")
    return runtime


def export_onnx(net: nn.Module, size: int, with_plate: bool) -> bytes:
    """The generator exported to ONNX (opset 17, batch axis dynamic), in memory.

    Args:
        net: the generator (its weights at the time of the call are exported).
        size: canvas size S.
        with_plate: whether ``forward`` takes a background plate (``net.config.uses_plate``).

    Returns:
        The serialised ONNX model; inputs ``x`` [B, C_in, S, S] (and ``plate`` [1, 3, S, S]), output ``frame``.
    """
    c_in = net.config.in_channels  # type: ignore[union-attr]
    x = torch.zeros(1, c_in, size, size)  # [1, C_in, S, S]
    args = (x, torch.zeros(1, 3, size, size)) if with_plate else (x,)
    names = ["x", "plate"] if with_plate else ["x"]
    buffer = io.BytesIO()
    with torch.no_grad(), warnings.catch_warnings():
        # The exporter warns that instance norm always uses input statistics: so does the eval-mode module.
        warnings.simplefilter("ignore")
        torch.onnx.export(net.eval(), args, buffer, input_names=names, output_names=["frame"],
                          dynamic_axes={"x": {0: "batch"}, "frame": {0: "batch"}}, opset_version=17,
                          dynamo=False)
    return buffer.getvalue()


class OnnxGenerator:
    """A generator exported to ONNX and run by ONNX Runtime; called like the torch module.

    Args:
        net: the generator (its weights at the time of the call are exported, :func:`export_onnx`).
        size: canvas size S.
        with_plate: whether ``forward`` takes a background plate (``net.config.uses_plate``).
        threads: ONNX Runtime's intra-op threads (default: torch's).

    Attributes:
        onnx: the serialised ONNX model the session runs.
        precision: ``fp32``, or ``int8`` for a quantised model (:mod:`clone.runtime.int8`).
    """

    def __init__(self, net: nn.Module, size: int, with_plate: bool, threads: int | None = None) -> None:
        self._start(export_onnx(net, size, with_plate), with_plate, threads, "fp32")

    @classmethod
    def from_onnx(cls, model: bytes, with_plate: bool, threads: int | None = None,
                  precision: str = "fp32") -> OnnxGenerator:
        """A session on an already serialised model (same inputs and output as :func:`export_onnx`'s)."""
        self = cls.__new__(cls)
        self._start(model, with_plate, threads, precision)
        return self

    def _start(self, model: bytes, with_plate: bool, threads: int | None, precision: str) -> None:
        import onnxruntime as ort

        options = ort.SessionOptions()
        options.intra_op_num_threads = threads or torch.get_num_threads()
        options.inter_op_num_threads = 1
        options.log_severity_level = 3  # errors only
        self.session = ort.InferenceSession(model, options, providers=["CPUExecutionProvider"])
        self.onnx = model
        self.with_plate = with_plate
        self.precision = precision

    def __call__(self, x: Tensor, plate: Tensor | None = None) -> Tensor:
        """The frame.

        Args:
            x: [B, C_in, S, S] CPU tensor, see :func:`clone.model.networks.generator_input`.
            plate: [1, 3, S, S] background plate in [-1, 1]; required when the generator uses one.

        Returns:
            [B, 3, S, S] CPU tensor.
        """
        feeds = {"x": np.ascontiguousarray(x.numpy(), dtype=np.float32)}
        if self.with_plate:
            if plate is None:
                raise ValueError("this generator composites over (or sees) a background plate; pass plate=")
            feeds["plate"] = np.ascontiguousarray(plate.numpy(), dtype=np.float32)
        return torch.from_numpy(self.session.run(None, feeds)[0])
