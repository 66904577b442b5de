"""clone.model.face: where the face is, its crops and the face pass that refines them (training beside the
generator without touching it, stored in the model, run by the drive)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from clone.model import face
from clone.train_ref import TrainConfig, Trainer, losses
from pose_io.layouts import get_layout


def _images(seed: int, size: int = 64, batch: int = 2) -> torch.Tensor:
    return torch.from_numpy(np.random.default_rng(seed).uniform(-1, 1, (batch, 3, size, size)).astype(np.float32))


def _batch(size: int = 64) -> dict[str, torch.Tensor]:
    batch = {k: _images(i, size) for i, k in enumerate(("pose_prev", "pose_cur", "frame_prev", "frame_cur", "plate"))}
    batch["face"] = torch.zeros(2, 1, size, size)
    batch["face"][0, :, 10:20, 30:40] = 1.0  # the second sample shows no face
    return batch


def test_face_boxes_centre_on_the_disc_and_mark_samples_without_a_face():
    disc = torch.zeros(2, 1, 64, 64)
    yy, xx = torch.meshgrid(torch.arange(64.0), torch.arange(64.0), indexing="ij")
    disc[0, 0] = ((xx - 40) ** 2 + (yy - 20) ** 2 <= 5 ** 2).float()
    boxes, present = face.face_boxes(disc, losses.FACE_CROP_RADII)
    assert present.tolist() == [True, False]
    torch.testing.assert_close(boxes[0].mean(dim=0), torch.tensor([40.0, 20.0]), atol=0.3, rtol=0)
    side = boxes[0, 1, 0] - boxes[0, 0, 0]
    assert side == pytest.approx(2 * losses.FACE_CROP_RADII * 5, rel=0.1)
    assert face.face_crops(torch.rand(2, 3, 64, 64), boxes).shape == (2, 3, face.FACE_CROP, face.FACE_CROP)


@pytest.mark.parametrize("radius", [6.4, 9.5, 13.69, 21.2])
def test_the_drive_crops_faces_at_the_scale_training_does(radius):
    """Training boxes come from the drawn disc's area, the drive's from the stored radius: the same crop."""
    layout = get_layout("body31")
    joints = np.full((len(layout), 2), np.nan, dtype=np.float32)
    joints[layout.index("nose")] = (60.0, 50.0)
    disc = torch.from_numpy(face.face_mask(joints, layout, radius, 128)[None, None].astype(np.float32))
    boxes, _ = face.face_boxes(disc, face.FACE_PASS_RADII)
    trained_half = float(boxes[0, 1, 0] - boxes[0, 0, 0]) / 2
    assert face.FACE_PASS_RADII * face.drawn_radius(radius) == pytest.approx(trained_half, rel=1e-5)
    # the stored radius alone would have been off by more than rounding
    assert abs(face.FACE_PASS_RADII * radius - trained_half) > 1e-3


def test_face_centres_are_the_mean_of_the_visible_face_points():
    layout = get_layout("body31")
    joints = np.full((3, len(layout), 2), np.nan, dtype=np.float32)
    joints[0, layout.index("nose")] = (10.0, 20.0)
    joints[0, layout.index("r_ear")] = (14.0, 24.0)
    joints[1, layout.index("l_eye")] = (5.0, 6.0)
    joints[:, layout.index("neck")] = (0.0, 0.0)  # not a face point
    centres = face.face_centres(joints, layout)
    np.testing.assert_allclose(centres[:2], [[12.0, 22.0], [5.0, 6.0]])
    assert np.isnan(centres[2]).all()
    # body15 has the nose alone
    body15 = face.face_centres(joints[:, :15], get_layout("body15"))
    np.testing.assert_allclose(body15[0], [10.0, 20.0])
    assert np.isnan(body15[1:]).all()


def test_the_blend_mask_is_whole_on_the_face_and_nothing_at_the_crop_edge():
    mask = face.blend_mask()[0, 0]
    n = face.FACE_CROP
    assert mask.shape == (n, n)
    assert mask[n // 2, n // 2] == 1.0
    assert mask[0].max() == 0.0 and mask[:, 0].max() == 0.0 and mask[-1].max() == 0.0
    row = mask[n // 2, n // 2:]
    assert bool((row[1:] <= row[:-1]).all())  # falling outward


def test_paste_puts_the_crop_back_where_it_was_cut():
    frame = torch.zeros(1, 3, 64, 64)
    boxes = face.boxes_around(torch.tensor([30.0]), torch.tensor([20.0]), torch.tensor([12.0]))
    delta = 0.5 * face.blend_mask().expand(1, 3, -1, -1)
    out = face.paste(frame, delta, boxes)
    assert out[0, :, 20, 30].tolist() == pytest.approx([0.5] * 3, abs=1e-3)
    assert out[0, :, 20, 30 + 13].abs().max() == 0.0  # outside the box: untouched
    assert out[0, :, 20 + 13, 30].abs().max() == 0.0
    # cutting the pasted frame again gives the delta back inside the disc
    again = face.face_crops(out, boxes)
    inner = face.blend_mask()[0, 0] == 1.0
    torch.testing.assert_close(again[0, :, inner], delta[0, :, inner], atol=0.03, rtol=0)


def test_a_new_face_pass_leaves_the_frame_as_it_is():
    passed = face.FacePass(face.build_face_pass().eval(), radius=5.0)
    frame, pose = _images(0, batch=3), _images(1, batch=3)
    centres = torch.tensor([[30.0, 20.0], [float("nan"), float("nan")], [60.0, 60.0]])
    with torch.no_grad():
        torch.testing.assert_close(passed(frame, pose, centres), frame, atol=0, rtol=0)


def test_the_face_pass_trains_beside_the_generator_without_changing_it():
    """The generator's weights after a few steps are the same bit for bit with the face pass or without, while
    the face pass and its discriminator learn; the face pass resumes from the trainer's state."""
    runs = {}
    for with_pass in (False, True):
        torch.manual_seed(0)
        config = TrainConfig(size=64, base_channels=8, disc_channels=8, face_pass=with_pass)
        trainer = Trainer(config, torch.device("cpu"))
        batch = _batch()
        for _ in range(3):
            logs = trainer.train_step(batch, batch["frame_prev"])
        runs[with_pass] = (trainer, logs)
    plain, passed = runs[False][0], runs[True][0]
    assert plain.face_pass is None
    for a, b in zip(plain.g.parameters(), passed.g.parameters()):
        assert torch.equal(a, b)
    logs = runs[True][1]
    assert {"face_pass_l1", "face_pass_gan", "face_pass_d"} <= set(logs) and np.isfinite(logs["face_pass_l1"])
    with torch.no_grad():  # it left its zero start
        assert passed.face_pass(torch.cat([_images(2), _images(3)], dim=1)).abs().max() > 0
    # resuming: a second trainer given the face pass's weights and the state steps alike
    torch.manual_seed(5)
    config = TrainConfig(size=64, base_channels=8, disc_channels=8, face_pass=True)
    net = face.build_face_pass()
    net.load_state_dict(passed.face_pass.state_dict())
    again = Trainer(config, torch.device("cpu"), face_pass=net)
    again.g.load_state_dict(passed.g.state_dict())
    again.load_state_dict(passed.state_dict())
    batch = _batch()
    assert passed.train_step(batch, batch["frame_prev"]) == again.train_step(batch, batch["frame_prev"])


def test_crops_are_kornias_crop_and_resize():
    from kornia.geometry.transform import crop_and_resize

    images = _images(4, size=80, batch=3)
    boxes = face.boxes_around(torch.tensor([30.0, 75.0, -3.0]), torch.tensor([40.0, 10.0, 50.0]),
                              torch.tensor([12.0, 20.3, 8.0]))  # inside, over the edge, partly outside
    expected = crop_and_resize(images, boxes, (face.FACE_CROP, face.FACE_CROP), align_corners=True)
    torch.testing.assert_close(face.face_crops(images, boxes), expected, atol=1e-4, rtol=0)
