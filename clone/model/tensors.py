"""Images <-> tensors: the one place where frames on disk meet the networks.

Frames on disk and in memory are ``[B, H, W, 3]`` uint8 RGB; the networks take and give ``[B, 3, H, W]``
float in [-1, 1]. Training (:mod:`clone.train_ref`) and driving (:mod:`clone.drive.run`) both convert here.
"""

from __future__ import annotations

import numpy as np
import torch
from torch import Tensor


def to_tensor(images: np.ndarray) -> Tensor:
    """Images as the networks take them.

    Args:
        images: [B, H, W, 3] uint8 RGB.

    Returns:
        [B, 3, H, W] float32 in [-1, 1], on the CPU.
    """
    t = torch.from_numpy(np.ascontiguousarray(images)).permute(0, 3, 1, 2)  # [B, 3, H, W]
    return t.float().div_(127.5).sub_(1.0)


def to_images(tensor: Tensor) -> np.ndarray:
    """Network output as images (values outside [-1, 1] are clipped).

    Args:
        tensor: [B, 3, H, W] float in [-1, 1], on any device.

    Returns:
        [B, H, W, 3] uint8 RGB.
    """
    x = ((tensor.detach().float().clamp(-1, 1) + 1.0) * 127.5).round().to(torch.uint8)
    return x.permute(0, 2, 3, 1).cpu().numpy()  # [B, H, W, 3]
