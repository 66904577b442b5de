"""train_ref.losses: weights on the person and the face, SSIM and Laplacian-pyramid terms; the face mask of
the data; bfloat16 on the CPU."""

from __future__ import annotations

import numpy as np
import pytest
import torch
import torch.nn.functional as F

from clone.train_ref import LossConfig, TrainConfig, Trainer, losses
from clone.train_ref.augment import warp_batch
from clone.train_ref.data import ReferenceData, face_mask, face_radius
from pose_io.layouts import get_layout
from retarget.training import distributed


def _images(seed: int = 0, size: int = 32) -> torch.Tensor:
    return torch.from_numpy(np.random.default_rng(seed).uniform(-1, 1, (2, 3, size, size)).astype(np.float32))


def test_person_weights_mark_where_the_frame_is_not_the_plate_and_the_face_on_top():
    plate = torch.full((1, 3, 64, 64), 1.0)
    real = plate.clone()
    real[:, :, 20:40, 28:36] = -0.5  # the person
    pose = torch.full_like(real, -1.0)
    face = torch.zeros(1, 1, 64, 64)
    face[:, :, 20:24, 30:34] = 1.0
    w = losses.person_weights(real, plate, pose, 4.0, face, 10.0)
    assert w[0, 0, 30, 32] == 5.0 and w[0, 0, 60, 5] == 1.0  # inside the person / far outside
    assert w[0, 0, 22, 32] == 15.0  # the face: person and face
    grow = max(1, round(losses.PERSON_GROW * 64 / 256))
    assert w[0, 0, 30, 35 + grow] == 5.0 and w[0, 0, 30, 36 + grow] == 1.0  # grown past the edge
    # Without a plate the pose map alone marks the person.
    pose[:, :, 10, 10] = 1.0
    w = losses.person_weights(real, None, pose, 2.0)
    assert w[0, 0, 10, 10] == 3.0 and w[0, 0, 30, 32] == 1.0


def test_reconstruction_terms_vanish_on_the_truth_and_grow_with_the_difference():
    real = _images()
    ones = torch.ones(2, 1, 32, 32)
    torch.testing.assert_close(losses.weighted_l1(real + 0.1, real, ones), F.l1_loss(real + 0.1, real))
    for term in (losses.ssim_loss, losses.laplacian_loss):
        assert term(real, real, ones).item() == pytest.approx(0.0, abs=1e-6)
        small = term(real + 0.05 * _images(1), real, ones).item()
        large = term(real + 0.3 * _images(1), real, ones).item()
        assert 0.0 < small < large


def test_the_laplacian_term_sees_lost_texture_that_l1_hardly_does():
    # A blur (lost texture) against a uniform shift of the same L1: the pyramid's fine bands tell them apart.
    real = _images(2, 64)
    blurred = F.avg_pool2d(real, 3, stride=1, padding=1, count_include_pad=False)
    shifted = real + (blurred - real).abs().mean()
    ones = torch.ones(2, 1, 64, 64)
    assert F.l1_loss(shifted, real).item() == pytest.approx(F.l1_loss(blurred, real).item(), rel=1e-4)
    assert losses.laplacian_loss(blurred, real, ones) > 10.0 * losses.laplacian_loss(shifted, real, ones)
    assert losses.ssim_loss(blurred, real, ones) > 2.0 * losses.ssim_loss(shifted, real, ones)


def test_face_mask_follows_the_face_points_and_the_warp():
    layout = get_layout("body31")
    joints = np.full((2, len(layout), 2), np.nan, np.float32)
    body = {"nose": (32, 12), "neck": (32, 18), "mid_hip": (32, 36), "r_hip": (29, 36), "l_hip": (35, 36),
            "r_knee": (29, 46), "l_knee": (35, 46), "r_ankle": (29, 56), "l_ankle": (35, 56),
            "r_eye": (31, 11), "l_eye": (33, 11)}
    for name, xy in body.items():
        joints[:, layout.index(name)] = xy
    radius = face_radius(joints, layout)
    assert radius == pytest.approx(max(3.0, 44 / 12.0), rel=0.05)  # nose-neck + neck-hip + hip-knee-ankle
    mask = face_mask(joints[0], layout, radius, 64)
    assert mask[11, 32] and not mask[30, 32]
    assert face_radius(joints[:, :15], get_layout("body15")) is None  # no face points to place it

    data = ReferenceData(np.zeros((2, 64, 64, 3), np.uint8), joints, np.ones(2, bool), 64, layout="body31")
    sample = data.batch(np.array([1]))
    assert sample["face"].shape == (1, 1, 64, 64) and sample["face"][0, 0, 11, 32] == 1.0
    shift = torch.tensor([[[1.0, 0.0, 10.0], [0.0, 1.0, 0.0]]])  # 10 pixels to the right
    warped = warp_batch(sample, shift)
    assert warped["face"][0, 0, 11, 42] > 0.5 and warped["face"][0, 0, 11, 32 - round(radius) - 1] < 0.5


def test_a_step_with_every_term_reports_them_and_lowers_the_weighted_l1():
    torch.manual_seed(0)
    loss = LossConfig(person=4.0, face=8.0, ssim=10.0, laplacian=100.0)
    trainer = Trainer(TrainConfig(size=32, base_channels=8, disc_channels=8, lr=1e-3, loss=loss, face_pass=False),
                      torch.device("cpu"))
    batch = {k: _images(i) for i, k in enumerate(("pose_prev", "pose_cur", "frame_prev", "frame_cur", "plate"))}
    batch["face"] = torch.zeros(2, 1, 32, 32)
    batch["face"][:, :, 4:10, 12:20] = 1.0
    first = trainer.train_step(batch, batch["frame_prev"])
    assert set(first) == {"l1", "gan", "fm", "d", "ssim", "laplacian"}
    for _ in range(4):
        last = trainer.train_step(batch, batch["frame_prev"])
    assert last["l1"] < first["l1"] and last["ssim"] < first["ssim"]


def test_bfloat16_on_the_cpu_only_where_it_has_the_instructions(monkeypatch):
    cpu = torch.device("cpu")
    monkeypatch.setattr(distributed, "cpu_has_bf16", lambda: True)
    assert distributed.amp_dtype(cpu, True, cpu=True) is torch.bfloat16
    assert distributed.amp_dtype(cpu, None, cpu=True) is None  # opt-in on the CPU
    assert distributed.amp_dtype(cpu, False, cpu=True) is None
    assert distributed.amp_dtype(cpu, True) is None  # callers that never train the CPU in bfloat16
    monkeypatch.setattr(distributed, "cpu_has_bf16", lambda: False)
    assert distributed.amp_dtype(cpu, True, cpu=True) is None


def test_the_face_discriminator_trains_beside_and_resumes():
    torch.manual_seed(0)
    config = TrainConfig(size=32, base_channels=8, disc_channels=8, loss=LossConfig(face_gan=1.0), face_pass=False)
    trainer = Trainer(config, torch.device("cpu"))
    batch = {k: _images(i) for i, k in enumerate(("pose_prev", "pose_cur", "frame_prev", "frame_cur", "plate"))}
    batch["face"] = torch.zeros(2, 1, 32, 32)
    batch["face"][0, :, 4:10, 12:18] = 1.0  # the second sample shows no face
    before = [p.detach().clone() for p in trainer.face_d.parameters()]
    first = trainer.train_step(batch, batch["frame_prev"])
    assert {"face_gan", "face_d"} <= set(first) and np.isfinite(first["face_gan"])
    assert any(not torch.equal(a, b) for a, b in zip(before, trainer.face_d.parameters()))
    state = trainer.state_dict()
    assert "face_discriminator" in state
    torch.manual_seed(1)
    again = Trainer(config, torch.device("cpu"))
    again.g.load_state_dict(trainer.g.state_dict())
    again.load_state_dict(state)
    assert trainer.train_step(batch, batch["frame_prev"]) == again.train_step(batch, batch["frame_prev"])
    # Without the weight there is no face discriminator at all.
    assert Trainer(TrainConfig(size=32, base_channels=8, disc_channels=8), torch.device("cpu")).face_d is None
