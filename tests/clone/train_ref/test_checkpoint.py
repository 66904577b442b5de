"""train_ref.checkpoint: the training state lives inside the model file, and --resume reads it from there."""

from __future__ import annotations

import shutil

import torch
from typer.testing import CliRunner

from clone.cli.main import app
from clone.model.reference import load_reference_model
from tests.clone.train_ref.helpers import one_line_error, train_args


def resume_args(poses, frames, out, steps: int) -> list[str]:
    return ["train-ref", str(poses), str(frames), "--out", str(out), "--steps", str(steps), "--threads", "1",
            "--resume"]


def assert_same_generator(a, b) -> None:
    for key, value in a.generator_state.items():
        torch.testing.assert_close(b.generator_state[key], value, rtol=0, atol=0)


def test_model_file_holds_the_training_state(reference, tmp_path):
    poses, frames = reference
    out = tmp_path / "ref.pt"
    assert CliRunner().invoke(app, train_args(poses, frames, out)).exit_code == 0
    training = torch.load(out, map_location="cpu", weights_only=True)["training"]
    assert {"steps", "seconds", "config", "device", "trainer", "rng"} <= set(training)
    assert training["steps"] == training["trainer"]["step"] == 3
    assert {"discriminator", "opt_g", "opt_d"} <= set(training["trainer"])
    assert training["config"]["size"] == 32 and training["device"] == "cpu"


def test_resume_continues_the_step_count(reference, tmp_path):
    poses, frames = reference
    out = tmp_path / "ref.pt"
    assert CliRunner().invoke(app, train_args(poses, frames, out)).exit_code == 0
    args = resume_args(poses, frames, out, 5)
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    assert load_reference_model(out).training["steps"] == 5
    assert "--size 64 differs" in one_line_error(CliRunner().invoke(app, args + ["--size", "64"]))
    missing = ["train-ref", str(poses), str(frames), "--out", str(tmp_path / "none.pt"), "--resume"]
    assert "nothing to resume" in one_line_error(CliRunner().invoke(app, missing))


def test_resumed_run_equals_an_uninterrupted_one(reference, tmp_path):
    poses, frames = reference
    straight, split = tmp_path / "straight.pt", tmp_path / "split.pt"
    assert CliRunner().invoke(app, train_args(poses, frames, straight, steps=4)).exit_code == 0
    assert CliRunner().invoke(app, train_args(poses, frames, split, steps=2)).exit_code == 0
    assert CliRunner().invoke(app, resume_args(poses, frames, split, 4)).exit_code == 0
    a, b = load_reference_model(straight), load_reference_model(split)
    assert a.training["steps"] == b.training["steps"] == 4
    assert_same_generator(a, b)
    assert a.plate is not None and a.plate.tobytes() == b.plate.tobytes()  # the resumed run kept its plate


def test_training_state_travels_with_the_model_file(reference, tmp_path):
    """No file beside the model: a moved model resumes exactly, and no other model's state can mix in."""
    poses, frames = reference
    straight, first = tmp_path / "straight.pt", tmp_path / "first" / "ref.pt"
    assert CliRunner().invoke(app, train_args(poses, frames, straight, steps=4)).exit_code == 0
    assert CliRunner().invoke(app, train_args(poses, frames, first, steps=2)).exit_code == 0
    assert sorted(p.name for p in first.parent.iterdir()) == ["ref.preview.png", "ref.pt"]
    moved = tmp_path / "second" / "moved.pt"
    moved.parent.mkdir()
    shutil.move(first, moved)
    result = CliRunner().invoke(app, resume_args(poses, frames, moved, 4))
    assert result.exit_code == 0, result.output
    assert_same_generator(load_reference_model(straight), load_reference_model(moved))


def test_resuming_a_model_without_training_state_is_one_clear_error(reference, tmp_path):
    poses, frames = reference
    out = tmp_path / "ref.pt"
    assert CliRunner().invoke(app, train_args(poses, frames, out)).exit_code == 0
    raw = torch.load(out, map_location="cpu", weights_only=True)
    stripped = tmp_path / "stripped.pt"
    torch.save({k: v for k, v in raw.items() if k != "training"}, stripped)
    before = stripped.read_bytes()
    line = one_line_error(CliRunner().invoke(app, resume_args(poses, frames, stripped, 5)))
    assert "no training state" in line and str(stripped) in line
    assert stripped.read_bytes() == before
    # The stripped model still loads as a whole, with the same generator.
    model = load_reference_model(stripped)
    assert model.training is None
    assert_same_generator(load_reference_model(out), model)


def test_format_1_models_load_but_cannot_resume(reference, tmp_path):
    """Version 1 kept only a record under ``training`` (the state was in a side file)."""
    poses, frames = reference
    out = tmp_path / "ref.pt"
    assert CliRunner().invoke(app, train_args(poses, frames, out)).exit_code == 0
    raw = torch.load(out, map_location="cpu", weights_only=True)
    record = {k: raw["training"][k] for k in ("steps", "seconds", "config", "device")}
    old = tmp_path / "old.pt"
    torch.save({**raw, "format_version": 1, "training": record}, old)
    model = load_reference_model(old)
    assert model.training["steps"] == 3
    assert_same_generator(load_reference_model(out), model)
    assert "no training state" in one_line_error(CliRunner().invoke(app, resume_args(poses, frames, old, 5)))


def test_damaged_training_state_is_one_clear_error(reference, tmp_path):
    poses, frames = reference
    out = tmp_path / "ref.pt"
    assert CliRunner().invoke(app, train_args(poses, frames, out)).exit_code == 0
    raw = torch.load(out, map_location="cpu", weights_only=True)
    raw["training"]["trainer"]["opt_g"] = {}
    torch.save(raw, out)
    assert "damaged training state" in one_line_error(CliRunner().invoke(app, resume_args(poses, frames, out, 5)))


def test_strip_keeps_everything_that_drives_and_drops_what_only_resuming_reads(reference, tmp_path):
    poses, frames = reference
    out, small = tmp_path / "ref.pt", tmp_path / "small.pt"
    assert CliRunner().invoke(app, train_args(poses, frames, out)).exit_code == 0
    before = out.read_bytes()
    result = CliRunner().invoke(app, ["strip", str(out), "--out", str(small)])
    assert result.exit_code == 0, result.output
    assert f"wrote {small}" in result.output and "cannot be resumed" in result.output
    assert out.read_bytes() == before and small.stat().st_size < out.stat().st_size
    full, stripped = load_reference_model(out), load_reference_model(small)
    assert set(stripped.training) == {"steps", "seconds", "config", "device"}  # the run's record stays
    assert {k: stripped.training[k] for k in ("steps", "config")} == {k: full.training[k] for k in ("steps", "config")}
    assert_same_generator(full, stripped)
    for field in ("generator_name", "generator_config", "canvas", "codes_weights", "codes_weights_path", "temporal"):
        assert getattr(stripped, field) == getattr(full, field), field
    for field in ("scale_stats", "track_summary"):  # hold arrays
        assert repr(getattr(stripped, field)) == repr(getattr(full, field)), field
    assert stripped.plate.tobytes() == full.plate.tobytes()
    assert stripped.reference_track.joints.tobytes() == full.reference_track.joints.tobytes()
    assert str(stripped.reference_codes) == str(full.reference_codes)
    assert "no training state" in one_line_error(CliRunner().invoke(app, resume_args(poses, frames, small, 5)))
    assert not list(tmp_path.glob(".*small*"))  # no temporary file left


def test_strip_never_replaces_a_file_unasked(reference, tmp_path):
    poses, frames = reference
    out = tmp_path / "ref.pt"
    assert CliRunner().invoke(app, train_args(poses, frames, out)).exit_code == 0
    before = out.read_bytes()
    for target in (out, tmp_path / "." / "ref.pt"):  # MODEL itself, spelt two ways
        assert "already exists" in one_line_error(CliRunner().invoke(app, ["strip", str(out), "--out", str(target)]))
    assert out.read_bytes() == before
    assert CliRunner().invoke(app, ["strip", str(out), "--out", str(out), "--overwrite"]).exit_code == 0
    assert out.stat().st_size < len(before) and "trainer" not in load_reference_model(out).training
    again = CliRunner().invoke(app, ["strip", str(out), "--out", str(tmp_path / "again.pt")])
    assert again.exit_code == 0  # a stripped model strips to itself
    twice = load_reference_model(tmp_path / "again.pt")
    assert set(twice.training) == set(load_reference_model(out).training)
    assert_same_generator(load_reference_model(out), twice)
