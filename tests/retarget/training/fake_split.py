"""A tiny stand-in for a motion-world split (swinging stick figures) and the settings the training tests share."""

from __future__ import annotations

import numpy as np
import torch

from pose_io import BODY15
from retarget.network.checkpoint import load_checkpoint
from retarget.training.config import TrainConfig
from retarget.training.data import CrossSamples

_PARENT = {
    "neck": "mid_hip", "nose": "neck", "r_shoulder": "neck", "r_elbow": "r_shoulder", "r_wrist": "r_elbow",
    "l_shoulder": "neck", "l_elbow": "l_shoulder", "l_wrist": "l_elbow", "r_hip": "mid_hip", "r_knee": "r_hip",
    "r_ankle": "r_knee", "l_hip": "mid_hip", "l_knee": "l_hip", "l_ankle": "l_knee",
}
_OFFSET = {
    "neck": (0, 0.5, 0), "nose": (0, 0.2, 0.06), "r_shoulder": (-0.18, 0, 0), "r_elbow": (0, -0.28, 0),
    "r_wrist": (0, -0.25, 0), "l_shoulder": (0.18, 0, 0), "l_elbow": (0, -0.28, 0), "l_wrist": (0, -0.25, 0),
    "r_hip": (-0.1, 0, 0), "r_knee": (0, -0.42, 0), "r_ankle": (0, -0.4, 0), "l_hip": (0.1, 0, 0),
    "l_knee": (0, -0.42, 0), "l_ankle": (0, -0.4, 0),
}


class FakeSplit:
    """A tiny stand-in for a motion-world split: swinging stick figures.

    Motions differ in swing amplitude, frequency and travel; characters in limb lengths; views in the
    yaw of an orthographic camera. ``rng`` tilts the camera a little, like the world's random pitch.
    """

    def __init__(self, motions: int = 4, characters: int = 3, views: int = 3, seed: int = 0) -> None:
        rng = np.random.default_rng(seed)
        self.num_motions, self.num_characters, self.num_views = motions, characters, views
        self.motions = [
            {"amp": rng.uniform(0.2, 0.9), "freq": rng.uniform(0.05, 0.2), "phase": rng.uniform(0, 6),
             "speed": rng.uniform(-0.02, 0.02)}
            for _ in range(motions)
        ]
        self.characters = [{n: rng.uniform(0.8, 1.25) for n in _PARENT} for _ in range(characters)]
        self.yaws = np.linspace(-1.0, 1.0, views)
        self.views = tuple(float(np.degrees(y)) for y in self.yaws)

    def window(self, motion, character, view, length=64, offset=0, rng=None):
        t = np.arange(offset, offset + length, dtype=np.float64)
        m, ch = self.motions[motion], self.characters[character]
        swing = m["amp"] * np.sin(2 * np.pi * m["freq"] * t + m["phase"])
        angle = {"r_elbow": swing, "r_wrist": swing + 0.3, "l_elbow": -swing, "l_wrist": 0.3 - swing,
                 "r_knee": -swing, "r_ankle": -1.2 * swing, "l_knee": swing, "l_ankle": 1.2 * swing}
        pos = {"mid_hip": np.stack([m["speed"] * t, 0.82 + 0.03 * np.abs(swing), 0.5 * m["speed"] * t], -1)}
        for name in _PARENT:  # parents come first in this dict
            a = angle.get(name, np.zeros_like(t))
            off = np.array(_OFFSET[name]) * ch[name]
            rotated = np.stack([np.full_like(a, off[0]), np.cos(a) * off[1] - np.sin(a) * off[2],
                                np.sin(a) * off[1] + np.cos(a) * off[2]], -1)
            pos[name] = pos[_PARENT[name]] + rotated
        xyz = np.stack([pos[n] for n in BODY15.joints], axis=1)  # [T, 15, 3]
        yaw = self.yaws[view] + (rng.uniform(-0.1, 0.1) if rng is not None else 0.0)
        x = np.cos(yaw) * xyz[..., 0] + np.sin(yaw) * xyz[..., 2]
        return np.stack([256 + 110 * x, 420 - 110 * xyz[..., 1]], -1).astype(np.float32)


TINY = TrainConfig(batch_size=4, samples_per_epoch=8, val_samples=4, stats_windows=32)


def batch_of(split, n=4, seed=0, variant="full"):
    """A batch of ``n`` cross samples of ``split`` as the loader stacks them."""
    samples = CrossSamples(split, 64, variant, n, seed)
    items = [samples.sample(0, i) for i in range(n)]
    return {
        "windows": torch.from_numpy(np.stack([it["windows"] for it in items])),
        "ids": torch.from_numpy(np.stack([it["ids"] for it in items])),
    }


def weights_of(path):
    """The state dict of the network a checkpoint holds."""
    return load_checkpoint(path).model.state_dict()


class CameraSplit(FakeSplit):
    """A FakeSplit that takes a camera spread: its pitch range widens the yaw tilt and perspective shrinks the
    figure, as a steep or near camera changes how tall a person looks."""

    def __init__(self) -> None:
        super().__init__()
        self.seen: list = []

    def window(self, motion, character, view, length=64, offset=0, rng=None, *, cameras=None):
        self.seen.append(cameras)
        out = super().window(motion, character, view, length, offset, rng)
        shrink = 0.6 if cameras is not None and cameras.perspective > 0 else 1.0
        return (out * shrink).astype(np.float32)
