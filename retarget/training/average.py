"""A running mean of a network's weights over the ends of epochs (what stochastic weight averaging keeps).

From one epoch to the next the weights wander around a good region and the root path, which the loss constrains
least, moves most with them; their mean over the late epochs of a run sits nearer its middle. In the fourth
fine-tuning run of the model card, the mean of epochs 20-66 had a lower validation pose error than every single
epoch measured but the best one, and a lower pose error on demo-like cloning pairs than every single epoch measured.
"""

from __future__ import annotations

from typing import Any

from torch import nn
from torch.optim.swa_utils import AveragedModel

from pose_io.errors import InputError


class WeightAverage:
    """The mean of a model's parameters and buffers at the end of epochs ``first``, ``first + 1``, ...
    (torch's :class:`~torch.optim.swa_utils.AveragedModel`, started at ``first``).

    Attributes:
        first: the first epoch (counted from 1) that enters the mean.
    """

    def __init__(self, first: int, model: nn.Module, state: dict[str, Any] | None = None) -> None:
        if first < 1:
            raise InputError(f"the weight average must start at epoch 1 or later, got {first}")
        self.first = first
        self._mean = AveragedModel(model, use_buffers=True)
        if state is not None:
            if state["first"] != first:
                raise InputError(f"this run averages the weights from epoch {state['first']}; resume with that")
            self._mean.load_state_dict(state["mean"])

    @property
    def count(self) -> int:
        """Epochs in the mean so far."""
        return int(self._mean.n_averaged)

    def update(self, epoch: int, model: nn.Module) -> bool:
        """Add the model's weights as they are at the end of ``epoch``; False (nothing added) before ``first``."""
        if epoch < self.first:
            return False
        self._mean.update_parameters(model)
        return True

    def module(self) -> nn.Module:
        """The network holding the mean (not a copy: save it, do not train it)."""
        return self._mean.module

    def state(self) -> dict[str, Any]:
        """What a checkpoint stores to resume the mean."""
        return {"first": self.first, "mean": {k: v.detach().clone() for k, v in self._mean.state_dict().items()}}
