"""A running mean of a network's weights over the ends of epochs (what stochastic weight averaging keeps).

From one epoch to the next the weights wander around a good region and the root path, which the loss constrains
least, moves most with them; their mean over the late epochs of a run sits nearer its middle. In the fourth
fine-tuning run of the model card, the mean of epochs 20-66 had a lower validation pose error than every single
epoch measured but the best one, and a lower pose error on demo-like cloning pairs than every single epoch measured.
"""

from __future__ import annotations

import copy
from typing import Any

import torch
from torch import nn

from pose_io.errors import InputError


class WeightAverage:
    """The mean of a model's parameters and buffers at the end of epochs ``first``, ``first + 1``, ...

    Attributes:
        first: the first epoch (counted from 1) that enters the mean.
        count: epochs in it so far.
    """

    def __init__(self, first: int, state: dict[str, Any] | None = None) -> None:
        if first < 1:
            raise InputError(f"the weight average must start at epoch 1 or later, got {first}")
        self.first = first
        self.count = 0
        self._mean: dict[str, torch.Tensor] = {}
        if state is not None:
            if state["first"] != first:
                raise InputError(f"this run averages the weights from epoch {state['first']}; resume with that")
            self.count = int(state["count"])
            self._mean = {k: v.clone() for k, v in state["mean"].items()}

    def update(self, epoch: int, model: nn.Module) -> bool:
        """Add the model's weights as they are at the end of ``epoch``; False (nothing added) before ``first``."""
        if epoch < self.first:
            return False
        self.count += 1
        for key, value in model.state_dict().items():
            value = value.detach().to("cpu", torch.float64)
            if key not in self._mean:
                self._mean[key] = value.clone()
            else:
                self._mean[key] += (value - self._mean[key]) / self.count
        return True

    def module(self, model: nn.Module) -> nn.Module:
        """A copy of ``model`` holding the mean (in the model's dtypes); ``model`` is left as it is."""
        current = model.state_dict()
        out = copy.deepcopy(model)
        out.load_state_dict({k: v.to(current[k].dtype) for k, v in self._mean.items()})
        return out

    def state(self) -> dict[str, Any]:
        """What a checkpoint stores to resume the mean."""
        return {"first": self.first, "count": self.count, "mean": {k: v.clone() for k, v in self._mean.items()}}
