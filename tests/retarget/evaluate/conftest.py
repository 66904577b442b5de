"""Fixtures of the evaluation tests: a tiny motion world and tiny untrained weights, built once per package."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
import torch

from retarget.network.checkpoint import save_checkpoint
from retarget.network.model import RetargetNet, variant_config
from retarget.network.preprocess import NormStats
from retarget.world import MotionWorld
from tests.retarget.evaluate.helpers import TINY


@pytest.fixture(scope="package")
def tiny_mocap(shared_dir: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Four clips in one folder: the world puts one motion group in each split (val: two takes of one walk)."""
    root = tmp_path_factory.mktemp("mocap")
    for rel in TINY:
        shutil.copy(shared_dir / "mocap" / rel, root / Path(rel).name)
    return root


@pytest.fixture(scope="package")
def cache(tiny_mocap: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("cache")
    MotionWorld.build(tiny_mocap, folder)  # the defaults `clone retarget eval` uses
    return folder


@pytest.fixture(scope="package")
def tiny_weights(tmp_path_factory: pytest.TempPathFactory) -> Path:
    torch.manual_seed(0)
    path = tmp_path_factory.mktemp("weights") / "tiny.pt"
    stats = NormStats(np.zeros((15, 2)), np.full((15, 2), 50.0))
    return save_checkpoint(path, RetargetNet(variant_config("full")), stats)
