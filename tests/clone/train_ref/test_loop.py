"""train_ref.loop through `clone train-ref`: what a run writes, where, and the options it refuses."""

from __future__ import annotations

import cv2
import torch
from typer.testing import CliRunner

from clone.cli.main import app
from clone.model.reference import FORMAT_VERSION, KIND, load_reference_model, preview_path
from clone.train_ref import TrainConfig, train_reference
from tests.clone.train_ref.helpers import one_line_error, train_args


def test_train_ref_writes_one_model_and_preview(reference, tmp_path):
    poses, frames = reference
    out = tmp_path / "m" / "ref.pt"
    result = CliRunner().invoke(app, train_args(poses, frames, out))
    assert result.exit_code == 0, result.output
    assert out.is_file() and preview_path(out).is_file()
    assert sorted(p.name for p in out.parent.iterdir()) == sorted([out.name, preview_path(out).name])
    raw = torch.load(out, map_location="cpu", weights_only=True)
    assert raw["kind"] == KIND and raw["format_version"] == FORMAT_VERSION
    model = load_reference_model(out)
    assert model.canvas.size == 32 and model.canvas.image_size == (96, 72)
    assert model.generator_config.depth == 3 and model.temporal
    assert model.training["steps"] == 3
    assert model.reference_track.num_frames == 24 and model.reference_track.layout == "body15"
    assert model.scale_stats is not None and model.scale_stats.foot_close > 0
    assert model.track_summary["usable_frames"] == 24
    preview = cv2.imread(str(preview_path(out)))
    assert preview.shape[1] == 3 * 32 and preview.shape[0] % 32 == 0
    # The stored generator rebuilds and runs without any flags, over the stored background plate.
    assert model.generator_config.alpha and model.plate is not None and model.plate.shape == (32, 32, 3)
    net = model.build_generator()
    assert net(torch.zeros(1, 6, 32, 32), model.plate_tensor()).shape == (1, 3, 32, 32)


def test_no_background_trains_without_a_plate(reference, tmp_path):
    poses, frames = reference
    out = tmp_path / "ref.pt"
    result = CliRunner().invoke(app, train_args(poses, frames, out, "--no-background", steps=1))
    assert result.exit_code == 0, result.output
    model = load_reference_model(out)
    assert model.plate is None and not model.generator_config.uses_plate
    assert model.build_generator()(torch.zeros(1, 6, 32, 32)).shape == (1, 3, 32, 32)
    # Resuming keeps the stored choice; asking for the other one is refused before any work.
    assert "background" in one_line_error(CliRunner().invoke(app, train_args(poses, frames, out, "--resume",
                                                                             "--background", steps=2)))
    resumed = CliRunner().invoke(app, train_args(poses, frames, out, "--resume", steps=2))
    assert resumed.exit_code == 0, resumed.output
    assert load_reference_model(out).plate is None


def test_default_out_is_ref_model_in_the_current_folder(reference, tmp_path, monkeypatch):
    poses, frames = reference
    monkeypatch.chdir(tmp_path)
    args = ["train-ref", str(poses), str(frames), "--size", "32", "--steps", "1", "--threads", "1"]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    assert (tmp_path / "ref_model.pt").is_file()
    # Never replaced without --resume or --overwrite.
    before = (tmp_path / "ref_model.pt").read_bytes()
    assert "already exists" in one_line_error(CliRunner().invoke(app, args))
    assert (tmp_path / "ref_model.pt").read_bytes() == before
    assert CliRunner().invoke(app, args + ["--overwrite"]).exit_code == 0


def test_bad_options_are_one_line_errors(reference, tmp_path):
    poses, frames = reference
    out = tmp_path / "ref.pt"
    assert "power of two" in one_line_error(CliRunner().invoke(app, train_args(poses, frames, out, "--size", "100")))
    assert "--align" in one_line_error(CliRunner().invoke(app, train_args(poses, frames, out, "--align", "pad")))
    assert "device" in one_line_error(CliRunner().invoke(app, train_args(poses, frames, out, "--device", "tpu")))
    assert not out.exists()


def test_progress_goes_to_the_callback(reference, tmp_path):
    from clone.train_ref import StepProgress, TrainConfig, train_reference

    poses, frames = reference
    seen: list[StepProgress] = []
    result = train_reference(poses, frames, tmp_path / "ref.pt", config=TrainConfig(size=32), steps=2,
                             device=torch.device("cpu"), progress=seen.append)
    reading = [p for p in seen if p.phase == "reading"]
    training = [p for p in seen if p.phase == "training"]
    assert [p.step for p in reading] == list(range(1, 25)) and reading[-1].total == 24
    assert [p.step for p in training] == [1, 2] and set(training[-1].losses) == {"l1", "gan", "fm", "d"}
    assert result.steps == result.steps_this_run == 2 and not result.interrupted


def test_the_learning_rate_follows_the_runs_budget(reference, tmp_path, monkeypatch):
    from clone.train_ref.trainer import Trainer

    poses, frames = reference
    seen: list[float] = []
    original = Trainer.set_lr

    def record(self, factor):
        seen.append(factor)
        original(self, factor)

    monkeypatch.setattr(Trainer, "set_lr", record)
    train_reference(poses, frames, tmp_path / "ref.pt", config=TrainConfig(size=32, lr_decay_from=0.5), steps=4,
                    device="cpu")
    assert seen == [1.0, 1.0, 1.0, 0.5]  # set before each step from the share done: 0, 1/4, 2/4, 3/4 of the steps
    stored = load_reference_model(tmp_path / "ref.pt").training["trainer"]
    assert stored["opt_g"]["param_groups"][0]["lr"] == 0.5 * TrainConfig().lr


def _distance(a, b) -> float:
    sa, sb = a.build_generator().state_dict(), b.build_generator().state_dict()
    return sum(float((sa[k].float() - sb[k].float()).abs().sum()) for k in sa)


def test_init_starts_from_another_models_networks(reference, tmp_path):
    poses, frames = reference
    first, scratch, started = tmp_path / "first.pt", tmp_path / "scratch.pt", tmp_path / "init.pt"
    assert CliRunner().invoke(app, train_args(poses, frames, first, steps=4)).exit_code == 0
    # From other random weights (another seed): --init must not be the seed's doing.
    train_reference(poses, frames, scratch, config=TrainConfig(size=32, seed=1), steps=1, device="cpu")
    result = CliRunner().invoke(app, train_args(poses, frames, started, "--init", str(first), steps=1))
    assert result.exit_code == 0, result.output
    a, b, c = (load_reference_model(p) for p in (first, started, scratch))
    # One step away from the model it started from, far from a run that started from random weights.
    assert _distance(b, a) < 0.05 * _distance(c, a)
    assert b.training["steps"] == 1
    # `--init none` is random weights, the same as no --init.
    plain, none = tmp_path / "plain.pt", tmp_path / "none.pt"
    assert CliRunner().invoke(app, train_args(poses, frames, plain, steps=1)).exit_code == 0
    assert CliRunner().invoke(app, train_args(poses, frames, none, "--init", "none", steps=1)).exit_code == 0
    assert _distance(load_reference_model(plain), load_reference_model(none)) == 0.0


def test_init_refuses_another_architecture_and_resume(reference, tmp_path):
    poses, frames = reference
    first = tmp_path / "first.pt"
    assert CliRunner().invoke(app, train_args(poses, frames, first, steps=1)).exit_code == 0
    line = one_line_error(CliRunner().invoke(app, train_args(poses, frames, tmp_path / "b.pt", "--init", str(first),
                                                             "--no-details")))
    assert "--init" in line and "pose layout" in line
    args = train_args(poses, frames, tmp_path / "c.pt", "--init", str(first))
    args[args.index("32")] = "64"  # --size 64 against a 32² generator
    line = one_line_error(CliRunner().invoke(app, args))
    assert "--init" in line and "differs" in line
    line = one_line_error(CliRunner().invoke(app, train_args(poses, frames, first, "--init", str(first), "--resume")))
    assert "--init" in line and "--resume" in line
    line = one_line_error(CliRunner().invoke(app, train_args(poses, frames, tmp_path / "d.pt", "--init",
                                                             str(tmp_path / "missing.pt"))))
    assert "--init" in line


def test_face_gan_is_stored_and_refused_where_it_cannot_work(reference, tmp_path):
    poses, frames = reference
    out = tmp_path / "face.pt"
    result = CliRunner().invoke(app, train_args(poses, frames, out, "--face-gan", "1", steps=2))
    assert result.exit_code == 0, result.output
    model = load_reference_model(out)
    assert model.training["config"]["loss"]["face_gan"] == 1.0
    assert "face_discriminator" in model.training["trainer"]  # kept for --resume
    line = one_line_error(CliRunner().invoke(app, train_args(poses, frames, tmp_path / "b.pt", "--face-gan", "1",
                                                             "--no-details")))
    assert "--face-gan" in line and "--no-details" in line
    line = one_line_error(CliRunner().invoke(app, train_args(poses, frames, out, "--face-gan", "1", "--resume")))
    assert "--face-gan" in line


def test_person_crops_train_on_a_window_and_the_model_drives_the_whole_canvas(reference, tmp_path, monkeypatch):
    import dataclasses

    from clone.train_ref import AugmentConfig, trainer

    poses, frames = reference
    widths = []
    step = trainer.Trainer.train_step

    def spy(self, sample, *args, **kwargs):
        widths.append(tuple(sample["frame_cur"].shape[-2:]))
        return step(self, sample, *args, **kwargs)

    monkeypatch.setattr(trainer.Trainer, "train_step", spy)
    # the letterboxed frame at 128² (crops are at least 64 pixels): room beside the performer
    config = TrainConfig(size=128, seed=0, canvas_mode="full", face_pass=False)
    out = tmp_path / "crop.pt"
    train_reference(poses, frames, out, steps=3, device="cpu",
                    config=dataclasses.replace(config, augment=AugmentConfig(person_crop=True)))
    assert len(widths) == 3 and all(h % 32 == 0 and w % 32 == 0 and min(h, w) >= 64 for h, w in widths)
    assert any(hw != (128, 128) for hw in widths)  # the performer does not fill the canvas
    model = load_reference_model(out)
    assert model.canvas.size == 128
    channels = model.generator_config.in_channels
    assert model.build_generator()(torch.zeros(1, channels, 128, 128), model.plate_tensor()).shape == (1, 3, 128, 128)


def test_a_run_started_from_another_model_takes_the_init_learning_rate(reference, tmp_path):
    poses, frames = reference
    first, started, kept = tmp_path / "first.pt", tmp_path / "init.pt", tmp_path / "kept.pt"
    config = TrainConfig(size=32, seed=0)
    train_reference(poses, frames, first, config=config, steps=1, device="cpu")
    train_reference(poses, frames, started, config=config, steps=1, device="cpu", init=first)
    train_reference(poses, frames, kept, config=TrainConfig(size=32, seed=0, init_lr=None), steps=1, device="cpu",
                    init=first)
    lr = {p.name: load_reference_model(p).training["config"]["lr"] for p in (first, started, kept)}
    assert lr == {"first.pt": config.lr, "init.pt": config.init_lr, "kept.pt": config.lr} and config.init_lr > config.lr
