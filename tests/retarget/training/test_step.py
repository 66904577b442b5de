"""retarget.training.step: one optimiser step, the characters' proportion table."""

from __future__ import annotations

import numpy as np
import torch

from retarget.network.model import RetargetNet
from retarget.training.augment import AugmentConfig
from retarget.training.config import TrainConfig
from retarget.training.data import split_statistics
from retarget.training.losses import objective
from retarget.training.step import batch_tensors, train_step
from tests.retarget.training.fake_split import FakeSplit, batch_of


def test_one_training_step_lowers_the_loss():
    torch.manual_seed(0)
    split = FakeSplit()
    config = TrainConfig(augment=AugmentConfig(clip_lengths=(64,), scale_range=(1.0, 1.0), flip_prob=0.0,
                                               noise_std=0.0, drop_prob=0.0))
    stats = split_statistics(split, 64, 32, 0)
    batch = batch_of(split)
    model = RetargetNet()
    optimizer = torch.optim.Adam(model.parameters(), lr=config.lr, amsgrad=True)

    def loss() -> float:
        model.eval()
        with torch.no_grad():
            inputs, targets = batch_tensors(batch["windows"], batch["ids"], stats, config, torch.Generator(), False)
            return float(objective(model, inputs, targets, stats, config.loss)["total"])

    before = loss()
    train_step(model, optimizer, batch, stats, config, torch.Generator().manual_seed(0))
    assert loss() < before


def test_character_proportions_are_standardised_log_ratios():
    from types import SimpleNamespace

    from retarget.training.step import character_proportions
    from retarget.world.characters import make_skeleton

    bodies = [make_skeleton(1.8), make_skeleton(1.2), make_skeleton(1.7, legs=1.1, head=0.9)]
    table = character_proportions(SimpleNamespace(characters=bodies))
    assert table.shape == (3, len(bodies[0].lengths)) and table.dtype == torch.float32
    torch.testing.assert_close(table.mean(dim=0), torch.zeros(table.shape[1]), atol=1e-5, rtol=0)
    logs = np.log(np.array([b.array / b.height for b in bodies]))
    expected = (logs - logs.mean(axis=0)) / (logs.std(axis=0) + 1e-9)
    np.testing.assert_allclose(table.numpy(), expected, atol=1e-5)
