"""The generator prior: synthetic performers as one training set, its run (resumable), the compact export, and
`clone train-ref` starting from it."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import torch
from typer.testing import CliRunner

from clone.cli.main import app
from clone.model.reference import load_reference_model
from clone.model.tensors import to_tensor
from clone.train_ref import TrainConfig, train_reference
from clone.train_ref import prior as prior_module
from clone.train_ref.checkpoint import load_init
from clone.train_ref.prior import PriorConfig, export_prior, matching_prior, render_performers, train_prior
from pose_io.errors import InputError
from tests.clone.test_cli_synth import write_walk_bvh
from tests.clone.train_ref.helpers import one_line_error, train_args

SMALL = PriorConfig(performers=3, frames=4, seed=5)


@pytest.fixture
def mocap(tmp_path: Path) -> Path:
    folder = tmp_path / "mocap"
    folder.mkdir()
    write_walk_bvh(folder / "walk_a.bvh", frames=12)
    write_walk_bvh(folder / "walk_b.bvh", frames=20)
    return folder


def test_performers_form_one_training_set_with_their_own_plates(mocap: Path) -> None:
    data, record = render_performers(mocap, SMALL, 64, TrainConfig(size=64))
    assert data.frames.shape == (12, 64, 64, 3) and data.layout.name == "body31"
    assert record.num_frames == 12 and record.layout == "body15"
    assert list(data.owner) == [0] * 4 + [1] * 4 + [2] * 4
    idx = np.array([0, 1, 4, 7, 8])
    # a clip's first frame has no predecessor: never the last frame of the performer before it
    assert list(data.previous(idx)) == [-1, 0, -1, 6, -1]
    sample = data.batch(idx)
    assert sample["has_prev"].tolist() == [False, True, False, True, False]
    assert float(sample["frame_prev"][2].abs().max()) == 0.0
    torch.testing.assert_close(sample["plate"], to_tensor(data.performer_plates[[0, 0, 1, 1, 2]]))
    # every performer is cut to its own canvas: the person fills a good part of it
    heights = [np.nanmax(record.joints[i * 4:(i + 1) * 4, :, 1]) - np.nanmin(record.joints[i * 4:(i + 1) * 4, :, 1])
               for i in range(3)]
    assert min(heights) > 0.4 * 64
    # the same seed draws the same performers
    again, _ = render_performers(mocap, SMALL, 64, TrainConfig(size=64))
    assert np.array_equal(again.frames, data.frames)


def test_clips_too_short_for_the_performers_are_an_error_not_a_hang(tmp_path: Path) -> None:
    folder = tmp_path / "short"
    folder.mkdir()
    write_walk_bvh(folder / "walk.bvh", frames=3)
    with pytest.raises(InputError, match="4 frames long"):
        render_performers(folder, SMALL, 64, TrainConfig(size=64))


def test_prior_run_resumes_on_its_performers_and_exports_a_compact_prior(mocap: Path, tmp_path: Path) -> None:
    run, small = tmp_path / "run.pt", tmp_path / "prior.pt"
    train_prior(mocap, run, config=TrainConfig(size=64), prior=SMALL, steps=2)
    model = load_reference_model(run)
    assert model.training["prior"] == SMALL.to_dict() and model.training["steps"] == 2
    # resumed with another PriorConfig: the stored performers are kept
    _, steps = train_prior(mocap, run, prior=PriorConfig(performers=9), steps=3, resume=True)
    assert steps == 3 and load_reference_model(run).training["prior"] == SMALL.to_dict()
    export_prior(run, small)
    compact = load_reference_model(small)
    assert all(v.dtype == torch.float16 for v in compact.generator_state.values() if v.is_floating_point())
    assert "opt_g" not in compact.training["trainer"] and "rng" not in compact.training
    assert small.stat().st_size < 0.6 * run.stat().st_size
    start, disc = load_init(small, TrainConfig(size=64))
    assert disc is not None
    full = load_reference_model(run).build_generator().state_dict()
    for k, v in start.build_generator().state_dict().items():
        torch.testing.assert_close(v, full[k], atol=2e-3, rtol=2e-3)  # float16 rounding only
    # a new run from the compact prior starts from its networks
    again = tmp_path / "again.pt"
    train_prior(mocap, again, config=TrainConfig(size=64, seed=3), prior=SMALL, steps=1, init=small)
    moved = load_reference_model(again).build_generator().state_dict()
    assert load_reference_model(again).training["config"]["lr"] == TrainConfig().lr  # the prior's, not init_lr
    scratch = tmp_path / "scratch.pt"
    train_prior(mocap, scratch, config=TrainConfig(size=64, seed=3), prior=SMALL, steps=1)
    fresh = load_reference_model(scratch).build_generator().state_dict()

    def gap(a: dict, b: dict) -> float:
        return sum(float((a[k] - b[k]).abs().sum()) for k in a)

    assert gap(moved, full) < 0.2 * gap(fresh, full)
    # only a prior run's model exports
    train_reference(*_reference(tmp_path), tmp_path / "ref.pt", config=TrainConfig(size=32), steps=1, device="cpu")
    with pytest.raises(Exception, match="not a generator prior"):
        export_prior(tmp_path / "ref.pt", tmp_path / "no.pt")


def _reference(tmp_path: Path) -> tuple[Path, Path]:
    from tests.clone.train_ref.helpers import figure_track, write_reference

    return write_reference(tmp_path / "figure", figure_track())


def test_train_ref_starts_from_the_shipped_prior_where_it_fits(mocap: Path, tmp_path: Path, monkeypatch,
                                                               reference) -> None:
    run, small = tmp_path / "run.pt", tmp_path / "prior.pt"
    # another seed than the reference runs' (whose random weights are seed 0's)
    train_prior(mocap, run, config=TrainConfig(size=32, seed=7), prior=SMALL, steps=2)
    export_prior(run, small)
    assert matching_prior(TrainConfig(size=32), small) == small
    assert matching_prior(TrainConfig(size=64), small) is None
    assert matching_prior(TrainConfig(size=32, pose_layout="body15"), small) is None
    monkeypatch.setattr(prior_module, "PACKAGED_PRIOR", small)
    poses, frames = reference
    result = CliRunner().invoke(app, train_args(poses, frames, tmp_path / "a.pt", steps=1))
    assert result.exit_code == 0 and "shipped generator prior" in result.output, result.output
    result = CliRunner().invoke(app, train_args(poses, frames, tmp_path / "b.pt", "--init", "none", steps=1))
    assert result.exit_code == 0 and "prior" not in result.output, result.output
    result = CliRunner().invoke(app, train_args(poses, frames, tmp_path / "d.pt", "--init", str(small), steps=1))
    assert result.exit_code == 0 and "shipped" not in result.output, result.output
    prior_g = load_reference_model(small).build_generator().state_dict()

    def distance(path: Path) -> float:
        g = load_reference_model(path).build_generator().state_dict()
        return sum(float((g[k] - prior_g[k]).abs().sum()) for k in g)

    assert distance(tmp_path / "a.pt") < 0.05 * distance(tmp_path / "b.pt")
    assert distance(tmp_path / "d.pt") < 0.05 * distance(tmp_path / "b.pt")
    # another size does not fit it: random weights, no line; named with --init it is an error
    args = ["train-ref", str(poses), str(frames), "--size", "64", "--steps", "1", "--threads", "1", "--device", "cpu"]
    result = CliRunner().invoke(app, [*args, "--out", str(tmp_path / "c.pt")])
    assert result.exit_code == 0 and "prior" not in result.output, result.output
    line = one_line_error(CliRunner().invoke(app, [*args, "--out", str(tmp_path / "e.pt"), "--init", str(small)]))
    assert "--init" in line


def test_the_shipped_prior_fits_train_ref_at_256_with_the_default_options() -> None:
    assert prior_module.PACKAGED_PRIOR.is_file()
    assert prior_module.PACKAGED_PRIOR.stat().st_size < 20 * 2**20  # the package grows by at most 20 MB
    assert matching_prior(TrainConfig(size=256)) == prior_module.PACKAGED_PRIOR
    assert matching_prior(TrainConfig(size=128)) is None
    stored = load_reference_model(prior_module.PACKAGED_PRIOR).training["prior"]
    assert PriorConfig.stored(stored).plain_share == 1.0  # the one measured: one-colour shirts


def test_train_prior_command(mocap: Path, tmp_path: Path) -> None:
    run, small = tmp_path / "run.pt", tmp_path / "prior.pt"
    args = ["train-prior", "--mocap", str(mocap), "--out", str(run), "--size", "32", "--performers", "2",
            "--frames", "3", "--steps", "1", "--threads", "1", "--device", "cpu"]
    result = CliRunner().invoke(app, [*args, "--export", str(small)])
    assert result.exit_code == 0, result.output
    assert load_reference_model(small).training["prior"]["performers"] == 2
    before = run.read_bytes()
    # an existing run is neither replaced nor resumed unasked
    assert "already exists" in one_line_error(CliRunner().invoke(app, args))
    assert run.read_bytes() == before
    assert "--export" in one_line_error(CliRunner().invoke(app, [*args, "--resume", "--export", str(run)]))
    line = one_line_error(CliRunner().invoke(app, [*args[:7], "--performers", "4000", "--frames", "1000",
                                                   "--size", "256", "--out", str(tmp_path / "big.pt")]))
    assert "GiB" in line
    assert "--mocap" in one_line_error(CliRunner().invoke(app, [*args[:1], "--mocap", str(tmp_path / "none"),
                                                                "--out", str(tmp_path / "x.pt")]))


def test_plain_shirts_are_drawn_and_older_runs_keep_their_patterned_performers(mocap: Path) -> None:
    patterned = replace(SMALL, plain_share=0.0)
    plain, _ = render_performers(mocap, SMALL, 64, TrainConfig(size=64))
    striped, _ = render_performers(mocap, patterned, 64, TrainConfig(size=64))
    # the same bodies, poses and rooms (no extra draw at share 0); only shirts change
    assert np.array_equal(plain.joints, striped.joints, equal_nan=True)
    assert not np.array_equal(plain.frames, striped.frames)
    stored = {k: v for k, v in patterned.to_dict().items() if k != "plain_share"}
    assert PriorConfig.stored(stored) == patterned and PriorConfig.stored(SMALL.to_dict()) == SMALL


def test_a_prior_with_exemplars_draws_them_from_each_performer_and_stores_no_bank(mocap, tmp_path):
    run = tmp_path / "ex_prior.pt"
    train_prior(mocap, run, config=TrainConfig(size=64, exemplar=True), prior=SMALL, steps=1)
    model = load_reference_model(run)  # a prior may read exemplars without a bank: a reference brings its own
    assert model.sees_exemplar and model.exemplars is None
    export_prior(run, tmp_path / "ex_small.pt")
    start, _ = load_init(tmp_path / "ex_small.pt", TrainConfig(size=64, exemplar=True))
    assert start.sees_exemplar
