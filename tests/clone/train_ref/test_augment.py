"""train_ref.augment: one warp for pose maps and frames, and the degraded previous frame."""

from __future__ import annotations

import numpy as np
import torch

from clone.model.tensors import to_tensor
from clone.train_ref import AugmentConfig, degrade_previous, random_affines, warp_batch


def test_augmentation_warps_pose_maps_and_frames_identically():
    gen = torch.Generator().manual_seed(0)
    img = np.zeros((2, 32, 32, 3), dtype=np.uint8)
    img[:, 8:24, 12:20] = 255  # the same white block in the pose maps and the frames
    x = to_tensor(img)
    sample = {"pose_prev": x, "pose_cur": x, "frame_prev": x, "frame_cur": x,
              "has_prev": torch.tensor([True, True])}
    m = random_affines(2, 32, AugmentConfig(rotation_deg=10, scale=0.1, translate=0.1), gen)
    assert not torch.allclose(m[0], m[1])
    out = warp_batch(sample, m)
    assert not torch.allclose(out["pose_cur"], x)
    for key in ("pose_prev", "frame_prev", "frame_cur"):
        torch.testing.assert_close(out[key], out["pose_cur"])
    # The identity warp changes nothing.
    ident = torch.tensor([[[1.0, 0, 0], [0, 1.0, 0]]]).repeat(2, 1, 1)
    torch.testing.assert_close(warp_batch(sample, ident)["frame_cur"], x, atol=1e-5, rtol=0)


def test_previous_frame_is_zeros_without_one_and_when_dropped():
    gen = torch.Generator().manual_seed(0)
    prev = torch.rand(4, 3, 8, 8) * 2 - 1
    has = torch.tensor([True, False, True, True])
    out = degrade_previous(prev, has, AugmentConfig(), dropout=0.0, generator=gen)
    assert torch.equal(out[1], torch.zeros(3, 8, 8))
    assert (out[0] - prev[0]).abs().mean() < 0.3 and not torch.equal(out[0], prev[0])
    assert degrade_previous(prev, has, AugmentConfig(), dropout=1.0, generator=gen).abs().max() == 0


def test_the_plate_is_warped_with_the_frames():
    gen = torch.Generator().manual_seed(0)
    rng = np.random.default_rng(0)
    frame = to_tensor(rng.integers(0, 256, (2, 32, 32, 3), dtype=np.uint8))
    sample = {"pose_prev": frame, "pose_cur": frame, "frame_prev": frame, "frame_cur": frame, "plate": frame,
              "has_prev": torch.tensor([True, True])}
    out = warp_batch(sample, random_affines(2, 32, AugmentConfig(rotation_deg=10, translate=0.1), gen))
    assert not torch.allclose(out["plate"], frame)
    torch.testing.assert_close(out["plate"], out["frame_cur"])  # still the background of the warped frame
