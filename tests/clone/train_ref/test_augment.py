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


def test_a_person_window_holds_the_person_and_a_margin_in_steps_of_the_stride():
    from clone.train_ref.augment import CROP_MARGIN, person_window

    body = np.array([[100.0, 20.0], [139.0, 239.0], [np.nan, np.nan]])  # a tall, narrow body; a missing joint
    gen = torch.Generator().manual_seed(0)
    margin = CROP_MARGIN * 220
    starts = set()
    for _ in range(20):
        x0, y0, w, h = person_window(body, 256, 64, gen)
        assert (w, h) == (128, 256)  # at least half the canvas; the full height the body needs
        assert x0 <= 100 - margin and x0 + w >= 140 + margin and 0 <= x0 <= 256 - w
        starts.add(x0)
    assert len(starts) > 3  # the window moves about the person
    wide = np.array([[10.0, 100.0], [199.0, 159.0]])
    x0, y0, w, h = person_window(wide, 256, 64, gen)
    assert w == 256 and h == 128 and y0 <= 100 - 9 and y0 + h >= 160 + 9  # 15 % of the body's 60 rows
    assert person_window(np.full((3, 2), np.nan), 64, 16, gen) is None
    assert person_window(body / 4, 64, 8, gen)[2:] == (64, 64)  # never under 64 pixels: the whole small canvas


def test_a_crop_cuts_every_map_alike_around_the_warped_joints():
    from clone.train_ref.augment import crop, person_window, warped_points

    pose = -torch.ones(1, 3, 128, 128)
    pose[..., 10:50, 28:36] = 1.0  # the body drawn where its joints are, after the warp
    frame = torch.rand(1, 3, 128, 128)
    sample = {"pose_prev": pose, "pose_cur": pose.clone(), "frame_prev": frame, "frame_cur": frame.clone(),
              "plate": frame.clone(), "face": torch.zeros(1, 1, 128, 128), "has_prev": torch.tensor([True])}
    shift = torch.tensor([[[1.0, 0.0, 6.0], [0.0, 1.0, -2.0]]])  # the warp moves joints 6 right, 2 up
    joints = np.array([[[22.0, 12.0], [29.0, 51.0]]])
    np.testing.assert_allclose(warped_points(joints, shift), [[[28.0, 10.0], [35.0, 49.0]]])
    window = person_window(warped_points(joints, shift)[0], 128, 16, torch.Generator().manual_seed(1))
    out = crop(sample, window)
    assert out["pose_cur"].shape == (1, 3, 64, 64) and out["face"].shape == (1, 1, 64, 64)
    assert torch.equal(out["has_prev"], sample["has_prev"])
    assert (out["pose_cur"] > 0).sum() == (pose > 0).sum()  # the whole body is inside
    torch.testing.assert_close(out["frame_cur"], out["plate"])  # one window for every map
    assert crop(sample, None)["frame_cur"].shape == (1, 3, 128, 128)
