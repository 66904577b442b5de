"""The proportion probe: it learns the training characters' proportions and is scored on the silhouette grids."""

from __future__ import annotations

from pathlib import Path

import pytest
import torch

from retarget.evaluate import EvalConfig
from retarget.evaluate.codes import code_grid, grid_inputs
from retarget.evaluate.probe import ProbeConfig, probe_silhouettes, train_probe
from retarget.evaluate.run import network_method
from retarget.world import MotionWorld
from retarget.world.characters import standard_proportions


def test_probe_learns_proportions_and_is_scored_on_the_grids(tiny_mocap: Path, cache: Path, tiny_weights: Path) -> None:
    world = MotionWorld.build(tiny_mocap, cache)
    train, test = world.split("train"), world.split("test")
    net = network_method(tiny_weights, refine_steps=0)[1]
    config = ProbeConfig(steps=300, samples=400, batch=32, rate=3e-3)
    probe = train_probe(train, net, config)
    grid = code_grid(train, EvalConfig(pairs=1), 0)  # training characters, seen in training
    truth = standard_proportions(train.characters)  # what it was trained to output
    with torch.inference_mode():
        out = probe(grid_inputs(net, train, grid, 30.0)).numpy()
    assert ((out - truth[grid[:, 1]]) ** 2).mean() < 0.5  # predicting the mean scores 1
    again = train_probe(train, net, config)
    assert all(torch.equal(a, b) for a, b in zip(probe.state_dict().values(), again.state_dict().values()))
    scores, errors = probe_silhouettes(probe, net, test, EvalConfig(pairs=1, code_grids=3))
    assert set(scores) == set(errors) == {"body"}
    assert -1.0 <= scores["body"] <= 1.0 and errors["body"] >= 0.0


def test_probe_config_refuses_nonsense() -> None:
    for bad in ({"steps": 0}, {"samples": 1}, {"batch": 0}, {"rate": 0.0}, {"noise": -1.0}):
        with pytest.raises(ValueError):
            ProbeConfig(**bad)
