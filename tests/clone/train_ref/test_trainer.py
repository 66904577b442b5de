"""train_ref.trainer: the previous-frame inputs and one training step."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from clone.train_ref import AugmentConfig, TrainConfig, Trainer


@pytest.mark.parametrize("background", [True, False])
@pytest.mark.parametrize("source", ["real", "generated"])
def test_previous_input_sources(source, background):
    torch.manual_seed(0)
    config = TrainConfig(size=32, base_channels=8, disc_channels=8, prev_source=source, prev_dropout=0.0,
                         augment=AugmentConfig(prev_jitter=0.0, prev_noise=0.0), background=background)
    trainer = Trainer(config, torch.device("cpu"))
    x = torch.rand(3, 3, 32, 32) * 2 - 1
    sample = {"pose_prev": x.flip(0), "pose_cur": x, "frame_prev": x, "frame_cur": x,
              "has_prev": torch.tensor([True, True, False])}
    if background:
        sample["plate"] = torch.rand(3, 3, 32, 32) * 2 - 1
    g_in, d_prev = trainer.previous_input(sample, torch.Generator().manual_seed(0))
    assert torch.equal(g_in[2], torch.zeros(3, 32, 32)) and torch.equal(d_prev[2], torch.zeros(3, 32, 32))
    if source == "real":
        torch.testing.assert_close(g_in[:2], x[:2])
    else:  # G's own frame for t-1, made from its pose map and no previous frame
        with torch.no_grad():
            plate = sample["plate"][:2] if background else None
            expected = trainer.generate(sample["pose_prev"][:2], torch.zeros(2, 3, 32, 32), plate)
        torch.testing.assert_close(d_prev[:2], expected)
        torch.testing.assert_close(g_in[:2], expected)
    losses = trainer.train_step(sample, g_in, d_prev)
    assert set(losses) == {"l1", "gan", "fm", "d"} and all(np.isfinite(v) for v in losses.values())


def test_trainer_steps_lower_l1_on_a_fixed_batch():
    torch.manual_seed(0)
    config = TrainConfig(size=32, base_channels=8, disc_channels=8, lr=1e-3)
    trainer = Trainer(config, torch.device("cpu"))
    rng = np.random.default_rng(0)
    batch = {k: torch.from_numpy(rng.uniform(-1, 1, (2, 3, 32, 32)).astype(np.float32))
             for k in ("pose_prev", "pose_cur", "frame_prev", "frame_cur", "plate")}
    first = trainer.train_step(batch, batch["frame_prev"])["l1"]
    for _ in range(4):
        last = trainer.train_step(batch, batch["frame_prev"])["l1"]
    assert last < first
    assert trainer.step_count == 5


def test_state_dict_round_trip_continues_identically():
    config = TrainConfig(size=32, base_channels=8, disc_channels=8)
    rng = np.random.default_rng(0)
    batch = {k: torch.from_numpy(rng.uniform(-1, 1, (1, 3, 32, 32)).astype(np.float32))
             for k in ("pose_prev", "pose_cur", "frame_prev", "frame_cur", "plate")}
    torch.manual_seed(0)
    a = Trainer(config, torch.device("cpu"))
    a.train_step(batch, batch["frame_prev"])
    torch.manual_seed(1)  # b starts from other weights; G's are copied, the rest comes from the state
    b = Trainer(config, torch.device("cpu"))
    b.g.load_state_dict(a.g.state_dict())
    b.load_state_dict(a.state_dict())
    assert b.step_count == 1
    assert a.train_step(batch, batch["frame_prev"]) == b.train_step(batch, batch["frame_prev"])


def test_the_background_plate_takes_the_loss_where_the_person_is_not():
    # A batch whose frames are the plate: G, starting mostly transparent, is already close and learns to be
    # transparent; without the plate it has to paint the whole frame.
    rng = np.random.default_rng(0)
    plate = torch.from_numpy(rng.uniform(-1, 1, (1, 3, 32, 32)).astype(np.float32))
    pose = torch.from_numpy(rng.uniform(-1, 1, (1, 3, 32, 32)).astype(np.float32))
    batch = {"pose_prev": pose, "pose_cur": pose, "frame_prev": plate, "frame_cur": plate, "plate": plate}
    l1 = {}
    for background in (True, False):
        torch.manual_seed(0)
        trainer = Trainer(TrainConfig(size=32, base_channels=8, disc_channels=8, background=background),
                          torch.device("cpu"))
        l1[background] = [trainer.train_step(batch, batch["frame_prev"])["l1"] for _ in range(3)]
    assert l1[True][0] < 0.5 * l1[False][0]
    assert l1[True][-1] < l1[True][0]
