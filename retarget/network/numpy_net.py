"""The retargeting network evaluated with numpy alone: the torch-free inference path.

The same layers as :class:`retarget.network.model.RetargetNet` (eval mode: dropout off), computed channels-last
(``[B, T, C]``) with im2col + one matrix product per convolution:

* motion encoder: reflection padding, kernel-8 stride-2 convolutions, LeakyReLU;
* static encoders: reflection padding, kernel-7 convolutions, LeakyReLU, max or average pooling by 2, a global
  pool over time and an optional 1x1 convolution;
* decoder: nearest x2 upsampling then a kernel-7 convolution, done *polyphase*: an output frame reads 4
  low-rate frames (taps that read the same upsampled sample are summed once, at load time), 4/7 of the
  work. The odd outputs' 4 frames are the even ones' one frame later, so one product over 4-frame windows
  gives two consecutive output frames per window, in order. At the ends, where the upsampled signal is
  reflected and the windows repeat the end frame instead, the first / last ``pad - 1`` outputs get a small
  correction: a product of the differences between the frames read and the end frame. The static codes are
  constant over time, so their part of the first decoder convolution is a per-sample bias.

Parity with the torch model is tested (``tests/retarget/network/test_numpy_net.py``: ~3e-6 in network units measured,
1e-4 allowed), and of the fast formulations with the plain ones (``test_numpy_net_parity.py``). On one core
one pass took 0.34 ms at 120 frames and 18.5 ms at 10,000, a torch forward of the same weights 0.95 and
29-36 ms (its time moves with the page faults of its allocations).
Weights come from a ``.npz`` written by :mod:`retarget.network.numpy_weights`.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from retarget.network.config import NetworkConfig, min_frames
from retarget.network.preprocess import POSE_CHANNELS


def _reflect(x: np.ndarray, pad: int) -> np.ndarray:
    """Reflection padding of [B, T, C] along time (as ``F.pad(..., mode="reflect")``)."""
    if pad == 0:
        return x
    return np.concatenate([x[:, pad:0:-1], x, x[:, -2 : -pad - 2 : -1]], axis=1)  # [B, T + 2 pad, C]


def _conv(x: np.ndarray, weight: np.ndarray, bias: np.ndarray | None, kernel: int, stride: int = 1) -> np.ndarray:
    """Valid convolution of padded [B, Tp, Cin] with ``weight`` [kernel * Cin, Cout] -> [B, To, Cout] (plus
    ``bias`` [Cout] unless None)."""
    b, tp, c = x.shape
    t = (tp - kernel) // stride + 1
    # In a contiguous x (here always a padded copy) the K frames an output reads are K * Cin consecutive
    # numbers: the columns are a strided view of x (np.ndarray over its memory: as_strided costs 10x the
    # time, for nothing more here), made contiguous in one copy.
    x = np.ascontiguousarray(x)
    windows = np.ndarray((b, t, kernel * c), x.dtype, x, 0, (x.strides[0], stride * x.strides[1], x.strides[2]))
    cols = np.ascontiguousarray(windows)  # [B, To, K * Cin]
    out = (cols.reshape(b * t, -1) @ weight).reshape(b, t, -1)  # [B, To, Cout]
    if bias is not None:
        out += bias
    return out


def _leaky(x: np.ndarray, slope: float) -> np.ndarray:
    """LeakyReLU in place."""
    if 0.0 <= slope <= 1.0:
        return np.maximum(x, x * slope, out=x)
    return np.where(x >= 0, x, x * slope)


def _im2col_weight(weight: np.ndarray) -> np.ndarray:
    """torch's [Cout, Cin, K] -> [K * Cin, Cout] (the row order of :func:`_conv`'s columns: tap, then channel)."""
    return np.ascontiguousarray(weight.transpose(2, 1, 0).reshape(-1, weight.shape[0]), dtype=np.float32)


def _matrix(a: np.ndarray) -> np.ndarray:
    """[rows..., outputs, Cout] -> float32 [rows, outputs * Cout] (either may be 0)."""
    return np.ascontiguousarray(a.reshape(math.prod(a.shape[:-2]), a.shape[-2] * a.shape[-1]), dtype=np.float32)


@dataclass(frozen=True, eq=False)
class _UpConv:
    """Nearest x2 upsampling + reflection padding + convolution, computed on the low-rate signal.

    Attributes:
        direct: [K * Cin, Cout] weight of the plain convolution (inputs too short for the rest).
        poly: [taps * Cin, 2 * Cout] weight of two outputs over ``taps`` low-rate frames: the window starting
            at frame ``j + first`` gives outputs ``2j - shift`` and ``2j - shift + 1`` (the even output ``2i``
            reads the window of ``i``, the odd one ``2i + 1`` the window ``shift`` frames later), so the rows
            of the product are the output frames in order.
        left, right: [pad // 2 * Cin, (pad - 1) * Cout] corrections of the first / last ``pad - 1`` outputs,
            which read the upsampled signal reflected beyond its ends (``u[-q] = u[q]``, ``u[2n - 1 + d] =
            u[2n - 1 - d]``) where the polyphase windows repeat the end frame: a product of the differences
            ``frame j - frame 0`` (``frame n - 1 - j - frame n - 1``), j = 1 .. pad // 2.
        bias: [Cout].
        kernel, pad: kernel and its padding.
        taps, first, shift: low-rate frames a polyphase output reads (``pad + 1``), where the even outputs'
            window starts (relative to ``i``), and how much later the odd outputs' window starts (1 when
            ``pad`` is odd, else 0).
    """

    direct: np.ndarray
    poly: np.ndarray
    left: np.ndarray
    right: np.ndarray
    bias: np.ndarray
    kernel: int
    pad: int
    taps: int
    first: int
    shift: int

    @classmethod
    def build(cls, weight: np.ndarray, bias: np.ndarray) -> _UpConv:
        """From torch's [Cout, Cin, K] weight (K odd) and [Cout] bias."""
        c_out, c_in, kernel = weight.shape
        pad = (kernel - 1) // 2
        # output 2i + phase reads upsampled samples 2i + phase + k - pad (k < kernel) = low-rate frames i + offset,
        # offset from (phase - pad) // 2 to (phase + pad) // 2: pad + 1 frames for either phase
        taps, first, shift = pad + 1, -pad // 2, pad % 2
        poly = np.zeros((taps, c_in, 2, c_out))  # [tap, Cin, output of the window, Cout], summed in float64
        ends = max(pad - 1, 0)
        left = np.zeros((pad // 2, c_in, ends, c_out))  # [j - 1, Cin, m, Cout]
        right = np.zeros_like(left)
        for k in range(kernel):
            w = weight[:, :, k].T  # [Cin, Cout]
            for phase in (0, 1):
                poly[(phase + k - pad) // 2 - first - phase * shift, :, phase ^ shift] += w
            for m in range(ends):
                # output m reads u[-q] = u[q] = frame q // 2 where the windows have frame 0; output 2n - 1 - m
                # reads u[2n - 1 + d] = u[2n - 1 - d] = frame n - 1 - d // 2 where they have frame n - 1
                for beyond, fix in ((pad - m - k, left), (k - pad - m, right)):
                    if beyond >= 2:
                        fix[beyond // 2 - 1, :, m] += w
        return cls(_im2col_weight(weight), _matrix(poly), _matrix(left), _matrix(right), bias.astype(np.float32),
                   kernel, pad, taps, first, shift)  # fmt: skip

    def __call__(self, a: np.ndarray, bias: np.ndarray | None = None) -> np.ndarray:
        """[B, n, Cin] -> [B, 2n, Cout]; ``bias`` [B or 1, 1, Cout] replaces the layer's own when given."""
        bias = self.bias if bias is None else bias
        b, n, _ = a.shape
        p = self.pad
        if n <= 2 * p + 2:  # too short for the ends to be apart: the plain way
            return _conv(_reflect(np.repeat(a, 2, axis=1), p), self.direct, bias, self.kernel)
        # windows of the first and last frames repeated (only the ends read them, and those are corrected below)
        before, after = -self.first, self.shift + self.first + p
        padded = np.concatenate([a[:, :1].repeat(before, 1), a, a[:, -1:].repeat(after, 1)], axis=1)
        both = _conv(padded, self.poly, None, self.taps)  # [B, n + shift, 2 Cout]: outputs 2j - shift, 2j - shift + 1
        out = both.reshape(b, 2 * (n + self.shift), -1)[:, self.shift : self.shift + 2 * n]  # [B, 2n, Cout] view
        out += bias
        if h := p // 2:
            head = (a[:, 1 : h + 1] - a[:, :1]).reshape(b, -1)  # [B, h Cin]: frames 1 .. h minus frame 0
            tail = (a[:, -2 : -h - 2 : -1] - a[:, -1:]).reshape(b, -1)  # frames n - 2 .. n - 1 - h minus n - 1
            out[:, : p - 1] += (head @ self.left).reshape(b, p - 1, -1)  # outputs 0 .. p - 2
            out[:, -1:-p:-1] += (tail @ self.right).reshape(b, p - 1, -1)  # outputs 2n - 1 .. 2n - p + 1
        return out


@dataclass(frozen=True, eq=False)
class _StaticEncoder:
    layers: tuple[tuple[np.ndarray, np.ndarray], ...]  # ([Cin * K, Cout], [Cout]) per convolution
    compress: tuple[np.ndarray, np.ndarray] | None  # ([C, code], [code])
    pool: str  # "max" | "avg"
    kernel: int

    def __call__(self, x: np.ndarray, slope: float) -> np.ndarray:
        """[B, T, 28] -> [B, code]."""
        pad = (self.kernel - 1) // 2
        for weight, bias in self.layers:
            x = _leaky(_conv(_reflect(x, pad), weight, bias, self.kernel), slope)
            b, t, c = x.shape
            pairs = x[:, : t - t % 2].reshape(b, t // 2, 2, c)  # [B, T/2, 2, C]
            x = pairs.max(axis=2) if self.pool == "max" else pairs.mean(axis=2)
        code = x.max(axis=1) if self.pool == "max" else x.mean(axis=1)  # [B, C]
        if self.compress is not None:
            code = code @ self.compress[0] + self.compress[1]
        return code


@dataclass(frozen=True)
class _Params:
    """Reads the torch model's state_dict entries, checking their shapes."""

    params: Mapping[str, np.ndarray]
    variant: str

    def get(self, name: str, shape: tuple[int, ...]) -> np.ndarray:
        value = np.asarray(self.params[name], dtype=np.float32)
        if value.shape != shape:
            raise ValueError(f"parameter {name}: shape {value.shape}, the {self.variant} network needs {shape}")
        return value

    def convs(self, prefix: str, widths: tuple[int, ...], kernel: int) -> list[tuple[np.ndarray, np.ndarray]]:
        """[(weight [Cout, Cin, K], bias [Cout])] of ``prefix.layers.i``."""
        return [
            (self.get(f"{prefix}.layers.{i}.weight", (c_out, c_in, kernel)), self.get(f"{prefix}.layers.{i}.bias", (c_out,)))
            for i, (c_in, c_out) in enumerate(itertools.pairwise(widths))
        ]

    def static_encoder(
        self, prefix: str, widths: tuple[int, ...] | None, code: int | None, pool: str, kernel: int
    ) -> _StaticEncoder | None:
        if widths is None:
            return None
        layers = tuple((_im2col_weight(w), b) for w, b in self.convs(prefix, widths, kernel))
        compress = None
        if code is not None:
            weight = self.get(f"{prefix}.compress.weight", (code, widths[-1], 1))
            compress = (np.ascontiguousarray(weight[:, :, 0].T), self.get(f"{prefix}.compress.bias", (code,)))
        return _StaticEncoder(layers, compress, pool, kernel)


class NumpyRetargetNet:
    """:class:`retarget.network.model.RetargetNet` in eval mode, evaluated with numpy.

    The methods take and give the torch model's layouts (``[B, C, T]`` float32), so either can stand in for
    the other at inference.

    Args:
        config: the architecture.
        params: the torch model's ``state_dict`` as float32 numpy arrays (same names).

    Raises:
        KeyError: a parameter the architecture needs is missing.
        ValueError: a parameter of the wrong shape.
    """

    def __init__(self, config: NetworkConfig, params: Mapping[str, np.ndarray]) -> None:
        self.config = c = config
        read = _Params(params, c.variant)
        self.motion = tuple((_im2col_weight(w), b) for w, b in read.convs("motion_encoder", c.motion_channels,
                                                                            c.motion_kernel))  # fmt: skip
        self.body = read.static_encoder("body_encoder", c.body_channels, c.body_code, "max", c.static_kernel)
        self.view = read.static_encoder("view_encoder", c.view_channels, c.view_code, "avg", c.static_kernel)
        motion_dim = c.motion_channels[-1]
        layers = read.convs("decoder", (motion_dim + c.body_dim + c.view_dim, *c.decoder_channels), c.decoder_kernel)
        first_w, first_b = layers[0]
        # the static codes' channels of the first decoder convolution, summed over taps: [Cb], [Cv] x Cout
        summed = first_w[:, motion_dim:].sum(axis=2).T  # [Cb + Cv, Cout]
        self._static_weights = (np.ascontiguousarray(summed[: c.body_dim]), np.ascontiguousarray(summed[c.body_dim :]))
        self.decoder = (_UpConv.build(first_w[:, :motion_dim], first_b),
                        *(_UpConv.build(w, b) for w, b in layers[1:]))  # fmt: skip
        # for the decoder's backward pass (motion-code refinement): each layer's transposed convolution as a
        # plain one over the zero-padded output gradient, taps reversed: [K * Cout, Cin]
        self._transposed = tuple(_im2col_weight((w[:, :motion_dim] if i == 0 else w).transpose(1, 0, 2)[:, :, ::-1])
                                 for i, (w, _) in enumerate(layers))  # fmt: skip

    @property
    def variant(self) -> str:
        return self.config.variant

    @property
    def min_frames(self) -> int:
        """Shortest input (a multiple of the downsampling factor) every layer can take."""
        return min_frames(self.config)

    # -- the torch model's interface ([B, C, T]) --------------------------------------------------------

    def encode_motion(self, x: np.ndarray) -> np.ndarray:
        """[B, 30, T] -> [B, 128, T/8] motion code."""
        return self._motion(np.asarray(x, np.float32).transpose(0, 2, 1)).transpose(0, 2, 1)

    def encode_body(self, x: np.ndarray) -> np.ndarray:
        """[B, 30, T] -> [B, Cb, 1] skeleton code (pose channels only)."""
        return self._encode_static(self.body, "skeleton", x)[:, :, None]

    def encode_view(self, x: np.ndarray) -> np.ndarray:
        """[B, 30, T] -> [B, Cv, 1] view code (pose channels only)."""
        return self._encode_static(self.view, "view", x)[:, :, None]

    def decode(self, motion: np.ndarray, body: np.ndarray | None = None, view: np.ndarray | None = None) -> np.ndarray:
        """([B, Cm, T'], [B or 1, Cb(, 1)], [B or 1, Cv(, 1)]) -> [B, 30, 8 T'] normalised poses."""
        m = np.asarray(motion, np.float32).transpose(0, 2, 1)  # [B, T', Cm]
        return self._decode(m, self._first_bias(body, view)).transpose(0, 2, 1)

    def run(self, x: np.ndarray, body: np.ndarray | None = None, view: np.ndarray | None = None) -> np.ndarray:
        """``decode(encode_motion(x), body, view)`` without leaving the channels-last layout: [B, 30, T] -> same."""
        m = self._motion(np.asarray(x, np.float32).transpose(0, 2, 1))  # [B, T/8, Cm]
        return self._decode(m, self._first_bias(body, view)).transpose(0, 2, 1)

    # -- channels-last internals -----------------------------------------------------------------------

    def _motion(self, x: np.ndarray) -> np.ndarray:
        """[B, T, 30] -> [B, T/8, Cm]."""
        pad, kernel, slope = (self.config.motion_kernel - 2) // 2, self.config.motion_kernel, self.config.negative_slope
        for weight, bias in self.motion:
            x = _leaky(_conv(_reflect(x, pad), weight, bias, kernel, stride=2), slope)
        return x

    def _encode_static(self, encoder: _StaticEncoder | None, name: str, x: np.ndarray) -> np.ndarray:
        if encoder is None:
            raise ValueError(f"the {self.variant!r} network has no {name} encoder")
        pose = np.asarray(x, np.float32)[:, :POSE_CHANNELS].transpose(0, 2, 1)  # [B, T, 28]
        return encoder(pose, self.config.negative_slope)  # [B, C]

    def _first_bias(self, body: np.ndarray | None, view: np.ndarray | None) -> np.ndarray:
        """[B or 1, 1, Cout]: the first decoder convolution's bias plus its static codes' constant part."""
        bias = self.decoder[0].bias[None]  # [1, Cout]
        for name, code, present, weight in (
            ("skeleton", body, self.body is not None, self._static_weights[0]),
            ("view", view, self.view is not None, self._static_weights[1]),
        ):
            if present != (code is not None):
                raise ValueError(f"the {self.variant!r} network {'needs' if present else 'takes no'} a {name} code")
            if code is not None:
                code = np.asarray(code, np.float32)
                bias = bias + code.reshape(code.shape[0] if code.ndim > 1 else 1, -1) @ weight  # [B or 1, Cout]
        return bias[:, None, :]  # [B or 1, 1, Cout]

    def _decode(self, m: np.ndarray, first_bias: np.ndarray, kept: list[np.ndarray] | None = None) -> np.ndarray:
        """[B, T', Cm] -> [B, 8 T', 30]; ``kept`` collects what :meth:`decode_backward` needs (each hidden layer's
        LeakyReLU slope per element)."""
        slope, last = self.config.negative_slope, len(self.decoder) - 1
        x = m
        for i, layer in enumerate(self.decoder):
            x = layer(x, first_bias if i == 0 else None)
            if i < last:
                if kept is not None:
                    kept.append(np.where(x > 0, np.float32(1), np.float32(slope)))
                x = _leaky(x, slope)
        return x

    def decode_backward(self, grad: np.ndarray, kept: list[np.ndarray]) -> np.ndarray:
        """The gradient of a loss with respect to the motion code [B, T', Cm], from its gradient ``grad`` with
        respect to the decoder's output [B, 8 T', 30] (channels-last) and the ``kept`` of the forward pass
        (:meth:`_decode`). The static codes are held fixed.

        Each layer backwards: the transposed convolution (a plain one over the output gradient padded with
        ``kernel - 1`` zeros, taps reversed), the reflection padding folded back onto the frames it copied, and
        the two copies of every upsampled frame summed.
        """
        kernel = self.config.decoder_kernel
        pad = (kernel - 1) // 2
        g = np.asarray(grad, np.float32)
        for i in range(len(self.decoder) - 1, -1, -1):
            if i < len(self.decoder) - 1:
                g = g * kept[i]
            b, length, c = g.shape
            zeros = np.zeros((b, kernel - 1, c), np.float32)
            padded = _conv(np.concatenate([zeros, g, zeros], axis=1), self._transposed[i], None, kernel)  # [B, L + 2 pad, Cin]
            up = padded[:, pad : pad + length].copy()  # [B, L, Cin]: the upsampled signal's gradient
            up[:, pad:0:-1] += padded[:, :pad]  # the left padding copied frames pad .. 1
            up[:, -2 : -pad - 2 : -1] += padded[:, pad + length :]  # the right padding frames L - 2 .. L - 1 - pad
            g = up[:, 0::2] + up[:, 1::2]  # [B, L / 2, Cin]
        return g
