"""A motion that never repeats itself, for the retrieval tests."""

from __future__ import annotations

import numpy as np

from pose_io.track import PoseTrack
from tests.figures import walking_figure

FRAMES = 160


def moving_figure(seed: int, frames: int = FRAMES, **figure: object) -> PoseTrack:
    """A walking figure whose joints also wander smoothly at random: a motion that never repeats itself."""
    base = walking_figure(frames, seed=seed, **figure)
    rng = np.random.default_rng(100 + seed)
    noise = rng.normal(0.0, 1.0, base.joints.shape)
    kernel = np.exp(-0.5 * (np.arange(-12, 13) / 5.0) ** 2)
    for j in range(noise.shape[1]):
        for c in range(2):
            noise[:, j, c] = np.convolve(noise[:, j, c], kernel / kernel.sum() * 6, mode="same")
    return base.replace(joints=base.joints + 25.0 * noise.astype(np.float32))
