"""A small driver track built in memory, and the packaged retargeting network."""

from __future__ import annotations

import pytest
import torch

from retarget.api import Retargeter, load_retargeter
from tests.figures import walking_figure

FRAMES = 48


@pytest.fixture(scope="package")
def driver():
    return walking_figure(FRAMES, dropped=0.02, seed=3)


@pytest.fixture(scope="package")
def retargeter() -> Retargeter:
    torch.set_num_threads(1)
    return load_retargeter()  # the packaged weights
