"""clone.model.tensors: uint8 RGB images <-> [-1, 1] tensors."""

from __future__ import annotations

import numpy as np
import torch

from clone.model.tensors import to_images, to_tensor


def test_images_round_trip_exactly():
    rng = np.random.default_rng(0)
    images = rng.integers(0, 256, (2, 5, 7, 3), dtype=np.uint8)  # [B, H, W, 3]
    x = to_tensor(images)
    assert x.shape == (2, 3, 5, 7) and x.dtype == torch.float32
    assert x.min() >= -1.0 and x.max() <= 1.0
    assert torch.equal(x[1, 2], torch.from_numpy(images[1, ..., 2]).float() / 127.5 - 1.0)  # channel 2 is blue
    back = to_images(x)
    assert back.dtype == np.uint8 and np.array_equal(back, images)


def test_known_values_and_clipping():
    x = torch.tensor([-1.0, 0.0, 1.0, -3.0, 3.0]).view(1, 1, 1, 5).expand(1, 3, 1, 5)  # [1, 3, 1, 5]
    assert to_images(x)[0, 0, :, 0].tolist() == [0, 128, 255, 0, 255]
    assert to_tensor(np.full((1, 1, 1, 3), 255, np.uint8)).eq(1.0).all()
