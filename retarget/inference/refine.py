"""Test-time refinement of a driver's motion code (torch).

The motion encoder is a fast, amortised guess: decoded with the driver's own skeleton and view codes, its code
gives back a damped copy of the driver (tall_man's real track keeps 0.91 of its range of motion through the
shipped network). A few Adam steps on the code alone, the network frozen, bring the driver's own pose back
(the pose channels; the root velocity is left out), and the refined code is then decoded with the reference's
codes. The root velocity comes from the encoder's code: refined, it follows the driver's body and view too
closely and the root path onto another body gets worse (measured on the validation split).

The driver's own skeleton and view codes are the mean over windows of the training length, as a reference's
skeleton code is (:meth:`RetargeterBase.reference_codes`), not one pool over a long window; its view code too is
the mean here (the reference's view pooling was chosen after this refinement, with it as it is). A pull towards the encoder's
code (``anchor``) keeps the refined code where the decoder was trained. The settings are
:class:`retarget.inference.config.InferenceConfig`'s ``refine_*``.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F

from retarget.inference.windows import sub_windows
from retarget.network.model import RetargetNet
from retarget.network.preprocess import pose_channels, velocity_channels


def window_static_codes(
    model: RetargetNet, x: torch.Tensor, length: int, stride: int
) -> tuple[torch.Tensor | None, torch.Tensor | None]:
    """Skeleton and view codes [B, C, 1] of each window of ``x`` [B, 30, T]: the mean of the codes of its
    sub-windows of ``length`` frames ``stride`` apart (the last one ending with the window), or of the whole
    window when it is shorter. None for a code the network lacks."""
    pieces, count = sub_windows(x, length, stride, torch.cat)  # [N * B, 30, length]

    def mean_code(encode) -> torch.Tensor:  # [N * B, C, 1] -> [B, C, 1]
        return encode(pieces).reshape(count, x.shape[0], -1, 1).mean(dim=0)

    body = mean_code(model.encode_body) if model.body_encoder is not None else None
    view = mean_code(model.encode_view) if model.view_encoder is not None else None
    return body, view


def refined_motion(
    model: RetargetNet, x: torch.Tensor, steps: int, rate: float, anchor: float, code_window: int, code_stride: int
) -> tuple[torch.Tensor, torch.Tensor]:
    """The encoder's motion code of ``x`` and the refined one.

    Runs with gradients whatever the caller's mode (``torch.no_grad`` or ``torch.inference_mode`` around it).

    Args:
        model: the network (its parameters are not changed and get no gradients).
        x: [B, 30, T] normalised driver windows.
        steps: Adam steps on the code.
        rate: Adam's learning rate.
        anchor: weight of the squared distance to the encoder's code, against the pose reconstruction error
            (both means over their elements).
        code_window: length of the sub-windows the driver's static codes are averaged over.
        code_stride: step between them.

    Returns:
        ``(encoded, refined)``, both [B, Cm, T/8], without gradients.
    """
    with torch.inference_mode(False), torch.enable_grad():
        x = x.clone()  # a tensor made in inference mode cannot enter a graph; its copy made here can
        with torch.no_grad():
            encoded = model.encode_motion(x)
            body, view = window_static_codes(model, x, code_window, code_stride)
        code = encoded.clone().requires_grad_(True)
        optimiser = torch.optim.Adam([code], lr=rate)
        target = pose_channels(x)
        windows = x.shape[0]  # losses are summed over windows, so each window's code moves as it would alone
        for _ in range(steps):
            loss = F.mse_loss(pose_channels(model.decode(code, body, view)), target)
            if anchor:
                loss = loss + anchor * F.mse_loss(code, encoded)
            (code.grad,) = torch.autograd.grad(loss * windows, code)  # the network's parameters get no gradient
            optimiser.step()
        return encoded, code.detach()


def decode_refined(
    model: RetargetNet, x: torch.Tensor, body: torch.Tensor | None, view: torch.Tensor | None,
    steps: int, rate: float, anchor: float, code_window: int, code_stride: int,
) -> torch.Tensor:  # fmt: skip
    """[B, 30, T] driver windows -> [B, 30, T] decoded with the static codes ``body`` and ``view`` ([1, C, 1]).

    The pose channels come from the motion code refined as :func:`refined_motion` does, the root velocity from
    the encoder's: both codes go through the decoder in one batch.
    """
    encoded, refined = refined_motion(model, x, steps, rate, anchor, code_window, code_stride)
    with torch.no_grad():
        both = model.decode(torch.cat([refined, encoded]), body, view)  # [2B, 30, T]
        return torch.cat([pose_channels(both[: len(x)]), velocity_channels(both[len(x) :])], dim=1)
