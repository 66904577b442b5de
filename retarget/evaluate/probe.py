"""A proportion probe: how far a single 2D window tells characters apart, measured by a network trained for that alone.

The skeleton-code silhouette (:mod:`retarget.evaluate.codes`) asks the skeleton encoder to cluster windows by
character across motions and views. How high it can go depends on the characters as much as on the encoder: when
they differ by a few per cent in their proportions, one foreshortened window says little about them. The probe is a
reference point from the data side (not a bound: encoders trained on more characters can score above it): a small
convolutional network sees the windows exactly as the encoders do (the
same preprocessing and statistics) and is trained on the training split for nothing but each character's bone
lengths over its height (log ratios, standardised); its outputs on the evaluated split's silhouette grids are
then scored as a skeleton code is. It is a reference point for the skeleton codes, not a retargeting method.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
from torch import nn

from pose_io.errors import InputError
from retarget.evaluate.codes import code_grid, grid_inputs, mean_and_error, silhouette
from retarget.evaluate.config import EvalConfig
from retarget.world.characters import standard_proportions
from retarget.world.split import WorldSplit

_CHUNK = 2000  # windows prepared at a time


@dataclass(frozen=True)
class ProbeConfig:
    """How the probe is trained.

    Attributes:
        steps: Adam steps (batches of ``batch`` windows).
        samples: training windows drawn once (motion, character and view uniformly; pitch 0), held in memory as
            [samples, 30, window] float32 (30,000 64-frame windows: 230 MB).
        batch: windows per step.
        rate: Adam's learning rate.
        noise: Gaussian noise added to the normalised inputs of every batch.
        seed: seeds the windows, the initial weights and the batches.
    """

    steps: int = 4000
    samples: int = 30_000
    batch: int = 128
    rate: float = 1e-3
    noise: float = 0.02
    seed: int = 0

    def __post_init__(self) -> None:
        if self.steps < 1 or self.samples < 2 or self.batch < 1 or self.rate <= 0 or self.noise < 0:
            raise ValueError("steps, batch >= 1, samples >= 2, rate > 0 and noise >= 0")


class ProportionProbe(nn.Module):
    """[N, 30, T] normalised windows -> [N, bones] standardised log(bone length / height)."""

    def __init__(self, bones: int, width: int = 96) -> None:
        super().__init__()
        act = nn.LeakyReLU(0.2)
        self.features = nn.Sequential(
            nn.Conv1d(30, width, 7, padding=3), act,
            nn.Conv1d(width, width, 7, stride=2, padding=3), act,
            nn.Conv1d(width, width, 7, stride=2, padding=3), act,
        )  # fmt: skip
        self.head = nn.Sequential(nn.Linear(width, width), act, nn.Linear(width, bones))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.head(self.features(x).amax(dim=-1))


def train_probe(
    train: WorldSplit, net: object, config: ProbeConfig = ProbeConfig(), fps: float = 30.0
) -> ProportionProbe:
    """The probe trained on ``train``'s windows, its inputs prepared as ``net``'s encoders see them.

    Args:
        train: the split whose characters it learns (the training split).
        net: a ``Retargeter`` whose preprocessing and statistics make the inputs.
        config: the training.
        fps: the world's frame rate.

    Raises:
        InputError: the split has no full-length window or fewer than two characters.
    """
    rng = np.random.default_rng([config.seed, 7])
    full = [m for m, lab in enumerate(train.window_labels) if lab.clip_frames - lab.start >= train.window_length]
    if not full or train.num_characters < 2:
        raise InputError(f"{train.name} split: too few windows or characters to train the proportion probe")
    motions = rng.choice(full, config.samples)
    characters = rng.integers(0, train.num_characters, config.samples)
    views = rng.integers(0, train.num_views, config.samples)
    x = torch.cat([
        grid_inputs(net, train, np.stack([motions[i:i + _CHUNK], characters[i:i + _CHUNK], views[i:i + _CHUNK]], 1), fps)
        for i in range(0, config.samples, _CHUNK)
    ]).cpu()  # fmt: skip
    y = torch.from_numpy(standard_proportions(train.characters)).float()[torch.from_numpy(characters)]
    torch.manual_seed(config.seed)
    probe = ProportionProbe(y.shape[1])
    optimiser = torch.optim.Adam(probe.parameters(), lr=config.rate)
    generator = torch.Generator().manual_seed(config.seed)
    for _ in range(config.steps):
        batch = torch.randint(0, config.samples, (config.batch,), generator=generator)
        picked = x[batch]
        inputs = picked + config.noise * torch.randn(picked.shape, generator=generator)
        loss = ((probe(inputs) - y[batch]) ** 2).mean()
        optimiser.zero_grad()
        loss.backward()
        optimiser.step()
    return probe.eval()


def probe_silhouettes(
    probe: ProportionProbe, net: object, split: WorldSplit, config: EvalConfig, fps: float = 30.0
) -> tuple[dict[str, float], dict[str, float]]:
    """The probe's outputs scored as skeleton codes on the silhouette grids of ``code_silhouettes`` (the same
    windows): ``({"body": mean}, {"body": standard error})`` over ``config.code_grids`` grids."""
    values = []
    for g in range(config.code_grids):
        grid = code_grid(split, config, g)
        with torch.inference_mode():
            out = probe(grid_inputs(net, split, grid, fps).cpu()).double().numpy()
        values.append(silhouette(out, grid[:, 1]))
    mean, error = mean_and_error(values)
    return {"body": mean}, {"body": error}
