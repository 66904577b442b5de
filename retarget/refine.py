"""Test-time refinement of a driver's motion code (torch).

The motion encoder is a fast, amortised guess: decoded with the driver's own skeleton and view codes, its code
gives back a damped copy of the driver (tall_man's real track keeps 0.91 of its range of motion through the
shipped network). A few Adam steps on the code alone, the network frozen, bring the driver's own pose back
(the pose channels; the root velocity is left out), and the refined code is then decoded with the reference's
codes. The root velocity comes from the encoder's code: refined, it follows the driver's body and view too
closely and the root path onto another body gets worse (measured on the validation split).

A pull towards the encoder's code (``anchor``) keeps the refined code where the decoder was trained. The settings
are :class:`retarget.inference.InferenceConfig`'s ``refine_*``.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F

from retarget.model import RetargetNet
from retarget.preprocess import POSE_CHANNELS


def refined_motion(
    model: RetargetNet, x: torch.Tensor, steps: int, rate: float, anchor: float
) -> tuple[torch.Tensor, torch.Tensor]:
    """The encoder's motion code of ``x`` and the refined one.

    Args:
        model: the network (its parameters are not changed and get no gradients).
        x: [B, 30, T] normalised driver windows.
        steps: Adam steps on the code.
        rate: Adam's learning rate.
        anchor: weight of the squared distance to the encoder's code, against the pose reconstruction error
            (both means over their elements).

    Returns:
        ``(encoded, refined)``, both [B, Cm, T/8], without gradients.
    """
    with torch.no_grad():
        encoded = model.encode_motion(x)
        body = model.encode_body(x) if model.body_encoder is not None else None
        view = model.encode_view(x) if model.view_encoder is not None else None
    code = encoded.clone().requires_grad_(True)
    optimiser = torch.optim.Adam([code], lr=rate)
    target = x[:, :POSE_CHANNELS]
    windows = x.shape[0]  # losses are summed over windows, so each window's code moves as it would alone
    with torch.enable_grad():
        for _ in range(steps):
            loss = F.mse_loss(model.decode(code, body, view)[:, :POSE_CHANNELS], target)
            if anchor:
                loss = loss + anchor * F.mse_loss(code, encoded)
            (code.grad,) = torch.autograd.grad(loss * windows, code)  # the network's parameters get no gradient
            optimiser.step()
    return encoded, code.detach()


def decode_refined(
    model: RetargetNet, x: torch.Tensor, body: torch.Tensor | None, view: torch.Tensor | None,
    steps: int, rate: float, anchor: float,
) -> torch.Tensor:  # fmt: skip
    """[B, 30, T] driver windows -> [B, 30, T] decoded with the static codes ``body`` and ``view``.

    The pose channels come from the motion code refined as :func:`refined_motion` does, the root velocity from
    the encoder's.
    """
    encoded, refined = refined_motion(model, x, steps, rate, anchor)
    with torch.no_grad():
        y = model.decode(refined, body, view)
        y[:, POSE_CHANNELS:] = model.decode(encoded, body, view)[:, POSE_CHANNELS:]
    return y
