"""Motion-code refinement with numpy alone: :mod:`retarget.inference.refine`'s Adam steps, without torch.

The same loss and steps as the torch version (the pose channels of the decoded code against the driver's, a
pull towards the encoder's code, each window's loss on its own), with the decoder's gradient worked out by
:meth:`retarget.network.numpy_net.NumpyRetargetNet.decode_backward` and Adam written out as ``torch.optim.Adam``
computes it (betas 0.9 and 0.999, eps 1e-8). Its results equal the torch backend's up to float32 rounding
(tested). This is what lets the default `clone retarget apply` refine codes in a process that never imports
torch.
"""

from __future__ import annotations

import numpy as np

from retarget.inference.windows import sub_windows
from retarget.network.numpy_net import NumpyRetargetNet
from retarget.network.preprocess import POSE_CHANNELS

BETAS = (0.9, 0.999)
EPS = 1e-8


def window_static_codes(
    model: NumpyRetargetNet, x: np.ndarray, length: int, stride: int
) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Skeleton and view codes [B, C] of each window of ``x`` [B, 30, T]: the mean of the codes of its
    sub-windows of ``length`` frames ``stride`` apart, or of the whole window when it is shorter (as
    :func:`retarget.inference.refine.window_static_codes`). None for a code the network lacks."""
    pieces, count = sub_windows(x, length, stride, np.concatenate)  # [N * B, 30, length]

    def mean_code(encode) -> np.ndarray:  # [N * B, C, 1] -> [B, C]
        return encode(pieces)[:, :, 0].reshape(count, x.shape[0], -1).mean(axis=0)

    body = mean_code(model.encode_body) if model.body is not None else None
    view = mean_code(model.encode_view) if model.view is not None else None
    return body, view


def refined_motion(
    model: NumpyRetargetNet, x: np.ndarray, steps: int, rate: float, anchor: float, code_window: int,
    code_stride: int,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The encoder's motion code of ``x`` [B, 30, T] and the refined one, both channels-last [B, T/8, Cm]
    (arguments as :func:`retarget.inference.refine.refined_motion`'s)."""
    x = np.asarray(x, np.float32)
    frames = x.transpose(0, 2, 1)  # [B, T, 30]
    encoded = model._motion(frames)  # [B, T/8, Cm]
    body, view = window_static_codes(model, x, code_window, code_stride)
    bias = model._first_bias(body, view)  # [B, 1, Cout]: each window decoded with its own static codes
    target = frames[..., :POSE_CHANNELS]
    code = encoded.copy()
    m, v = np.zeros_like(code), np.zeros_like(code)
    # each window's loss is a mean over its own elements (the torch version sums the windows' mean losses)
    pose_scale = np.float32(2.0 / (target.shape[1] * target.shape[2]))
    anchor_scale = np.float32(2.0 * anchor / (code.shape[1] * code.shape[2]))
    (b1, b2), lr = BETAS, np.float32(rate)
    for t in range(1, steps + 1):
        kept: list[np.ndarray] = []
        out = model._decode(code, bias, kept)  # [B, T, 30]
        grad_out = np.zeros_like(out)
        grad_out[..., :POSE_CHANNELS] = pose_scale * (out[..., :POSE_CHANNELS] - target)
        grad = model.decode_backward(grad_out, kept)
        if anchor:
            grad += anchor_scale * (code - encoded)
        m = np.float32(b1) * m + np.float32(1 - b1) * grad
        v = np.float32(b2) * v + np.float32(1 - b2) * grad * grad
        denom = np.sqrt(v) / np.float32(np.sqrt(1 - b2**t)) + np.float32(EPS)
        code = code - (lr / np.float32(1 - b1**t)) * m / denom
    return encoded, code


def decode_refined(
    model: NumpyRetargetNet, x: np.ndarray, body: np.ndarray | None, view: np.ndarray | None,
    steps: int, rate: float, anchor: float, code_window: int, code_stride: int,
) -> np.ndarray:  # fmt: skip
    """[B, 30, T] driver windows -> [B, 30, T] decoded with the reference's ``body`` and ``view`` codes: the pose
    channels from the refined motion code, the root velocity from the encoder's (as
    :func:`retarget.inference.refine.decode_refined`)."""
    encoded, refined = refined_motion(model, x, steps, rate, anchor, code_window, code_stride)
    both = model._decode(np.concatenate([refined, encoded]), model._first_bias(body, view))  # [2B, T, 30]
    out = both[len(x) :].copy()
    out[..., :POSE_CHANNELS] = both[: len(x), :, :POSE_CHANNELS]
    return out.transpose(0, 2, 1)
