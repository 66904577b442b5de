"""A reference model whose generator reads exemplars: trained, stored, started from a model without them, driven."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import torch

from clone.model.networks import composite
from clone.model.reference import load_reference_model, save_reference_model
from clone.runtime.generate import generate_frames
from clone.runtime.pose_maps import draw_exemplars
from clone.train_ref import TrainConfig, train_reference
from clone.train_ref.checkpoint import with_exemplar_input
from pose_io.errors import InputError

CONFIG = TrainConfig(size=32, seed=0, exemplar=True)


@pytest.fixture
def exemplar_model(reference, tmp_path):
    poses, frames = reference
    out = tmp_path / "ex.pt"
    train_reference(poses, frames, out, config=CONFIG, steps=2, device="cpu")
    return out


def test_a_run_with_exemplars_stores_its_bank_and_drives_with_it(exemplar_model, tmp_path):
    model = load_reference_model(exemplar_model)
    assert model.sees_exemplar and model.generator_config.in_channels == 9
    bank = model.exemplars
    assert bank is not None and 1 <= len(bank) <= 24 and bank.images.shape[1:] == (32, 32, 3)
    track = model.reference_track.frames(0, 6)
    frames = [f for _m, f in generate_frames(model, track, "cpu", runtime="torch")]
    assert len(frames) == 6 and frames[0].shape == (32, 32, 3)
    # the exemplars are read: other bank pictures give other frames
    dark = dataclasses.replace(model, exemplars=dataclasses.replace(bank, images=np.zeros_like(bank.images)))
    other = [f for _m, f in generate_frames(dark, track, "cpu", runtime="torch")]
    assert np.abs(np.stack(other).astype(int) - np.stack(frames).astype(int)).max() > 0
    # a frame without a pose gets a black exemplar, not a bank frame at the origin
    empty = track.replace(joints=np.where(np.arange(6)[:, None, None] == 2, np.nan, track.joints).astype(np.float32))
    exemplars = np.concatenate(list(draw_exemplars(model, empty)))
    assert exemplars[2].max() == 0 and exemplars[1].max() > 0


def test_a_model_without_exemplars_starts_a_run_that_reads_them(reference, tmp_path):
    poses, frames = reference
    plain = tmp_path / "plain.pt"
    train_reference(poses, frames, plain, config=TrainConfig(size=32, seed=0), steps=1, device="cpu")
    model = load_reference_model(plain)
    grown = with_exemplar_input(model)
    assert grown.generator_config.in_channels == model.generator_config.in_channels + 3
    assert grown.generator_config.exemplar and not model.generator_config.exemplar
    a, b = model.build_generator(), grown.build_generator()
    x, plate = torch.rand(1, 6, 32, 32) * 2 - 1, model.plate_tensor()
    heads = []
    a.head.register_forward_hook(lambda _m, _i, out: heads.append(out))
    with torch.no_grad():
        a(x, plate)
        rgb, alpha = heads[0][:, :3], heads[0][:, 3:]
        for exemplar in (torch.zeros(1, 3, 32, 32), torch.rand(1, 3, 32, 32) * 2 - 1):
            # it paints what the old one painted and starts with a half-and-half blend of the exemplar
            want = composite(torch.cat([0.5 * exemplar + 0.5 * rgb, alpha], 1), plate)
            torch.testing.assert_close(b(torch.cat([x, exemplar], 1), plate), want)
    started = tmp_path / "started.pt"
    train_reference(poses, frames, started, config=CONFIG, steps=1, device="cpu", init=plain)
    assert load_reference_model(started).exemplars is not None


def test_a_model_that_reads_exemplars_without_its_bank_does_not_load(exemplar_model, tmp_path):
    model = load_reference_model(exemplar_model)
    broken = tmp_path / "broken.pt"
    save_reference_model(dataclasses.replace(model, exemplars=None), broken)
    with pytest.raises(InputError, match="exemplar"):
        load_reference_model(broken)


def test_train_ref_takes_exemplars_on_request_and_keeps_the_choice_when_resuming(reference, tmp_path):
    from typer.testing import CliRunner

    from clone.cli.main import app
    from tests.clone.train_ref.helpers import one_line_error, train_args

    poses, frames = reference
    out = tmp_path / "ref.pt"
    result = CliRunner().invoke(app, train_args(poses, frames, out, "--exemplars", steps=1))
    assert result.exit_code == 0, result.output
    assert load_reference_model(out).exemplars is not None
    line = one_line_error(CliRunner().invoke(app, train_args(poses, frames, out, "--resume", "--no-exemplars",
                                                             steps=2)))
    assert "exemplars" in line
    assert load_reference_model(out).training["steps"] == 1  # nothing was overwritten
    plain = tmp_path / "plain.pt"
    assert CliRunner().invoke(app, train_args(poses, frames, plain, steps=1)).exit_code == 0
    assert load_reference_model(plain).exemplars is None  # off below 128² by default
