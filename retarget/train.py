"""Training the retargeting network on the synthetic motion world: the import surface of :mod:`retarget.training`.

The code lives in :mod:`retarget.training` (config, data, step, loop, run); this module keeps the names
importable where they always were (``from retarget.train import TrainConfig, fit, train``).
"""

from retarget.training.config import TrainConfig
from retarget.training.data import (
    CrossSamples,
    WorldSplit,
    body_scales,
    character_heights,
    mean_pose_height,
    real_windows,
    split_statistics,
)
from retarget.training.loop import CPU, DEFAULT_EPOCHS, TrainSummary, fit, retargeting_error
from retarget.training.run import read_real_tracks, train
from retarget.training.state import ProgressFn, TrainProgress
from retarget.training.step import TrainLoss, batch_tensors, evaluate, part_tensors, train_step

__all__ = [
    "CPU",
    "DEFAULT_EPOCHS",
    "CrossSamples",
    "ProgressFn",
    "TrainConfig",
    "TrainLoss",
    "TrainProgress",
    "TrainSummary",
    "WorldSplit",
    "batch_tensors",
    "body_scales",
    "character_heights",
    "evaluate",
    "fit",
    "mean_pose_height",
    "part_tensors",
    "read_real_tracks",
    "real_windows",
    "retargeting_error",
    "split_statistics",
    "train",
    "train_step",
]
