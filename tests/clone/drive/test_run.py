"""drive: train-ref -> drive round trips through the CLI, output checks, and bad model files."""

from __future__ import annotations

import shutil
import threading
from pathlib import Path

import imageio_ffmpeg
import numpy as np
import pytest
import torch
from typer.testing import CliRunner

from clone.cli.main import app
from clone.drive.poses import drive_poses, move_onto_reference
from clone.drive.run import drive
from clone.drive.stage import reference_stage
from clone.model.reference import file_sha256, load_reference_model
from clone.runtime.generate import generate_frames
from clone.runtime.onnx import onnx_available
from pose_io.errors import InputError
from pose_io.readers import read_track
from pose_io.writers import write_track
from retarget import api as retarget_api
from tests.clone.train_ref.helpers import (  # noqa: F401 (_restore_threads is an autouse fixture)
    _restore_threads,
    figure_track,
    one_line_error,
    train_args,
    write_reference,
)


@pytest.fixture
def driver(tmp_path: Path) -> Path:
    """A smaller figure in a bigger frame, 30 frames at 12 fps."""
    return write_track(figure_track(30, width=160, height=120, scale=0.7, phase=5.0, fps=12.0), tmp_path / "drv")


def read_video(path: Path) -> tuple[list[np.ndarray], float, tuple[int, int]]:
    gen = imageio_ffmpeg.read_frames(str(path))
    meta = next(gen)
    w, h = meta["size"]
    frames = [np.frombuffer(f, np.uint8).reshape(h, w, 3) for f in gen]
    return frames, float(meta["fps"]), (w, h)


def drive_args(driver: Path, out: Path, model: Path, *extra: str) -> list[str]:
    return ["drive", str(driver), "--out", str(out), "--model", str(model), "--threads", "1", "--device", "cpu",
            *extra]


def test_round_trip_writes_a_playable_mp4(trained, driver, tmp_path):
    out = tmp_path / "out.mp4"
    result = CliRunner().invoke(app, drive_args(driver, out, trained, "--method", "global-scale"))
    assert result.exit_code == 0, result.output
    frames, fps, size = read_video(out)
    assert len(frames) == 30 and fps == pytest.approx(12.0) and size == (32, 32)
    assert np.std(np.stack(frames)) > 1.0  # not a blank video


def test_side_by_side_and_poses_out(trained, driver, tmp_path):
    out, poses_out = tmp_path / "sbs.mp4", tmp_path / "driven"
    args = drive_args(driver, out, trained, "--method", "none", "--side-by-side", "--poses-out", str(poses_out))
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    frames, _, size = read_video(out)
    assert size == (96, 32) and len(frames) == 30
    driven = read_track(poses_out)
    assert driven.num_frames == 30 and driven.layout == "body15"
    model = load_reference_model(trained)
    assert driven.image_size == model.canvas.image_size
    # --method none keeps the driver's coordinates.
    np.testing.assert_allclose(driven.joints, read_track(driver).joints, atol=1e-3)


def test_existing_output_is_kept_unless_overwrite(trained, driver, tmp_path):
    out = tmp_path / "out.mp4"
    out.write_bytes(b"mine")
    args = drive_args(driver, out, trained, "--method", "none")
    assert "already exists" in one_line_error(CliRunner().invoke(app, args))
    assert out.read_bytes() == b"mine"
    assert CliRunner().invoke(app, args + ["--overwrite"]).exit_code == 0
    assert len(read_video(out)[0]) == 30


def test_default_model_path(trained, driver, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    trained.rename(tmp_path / "ref_model.pt")
    result = CliRunner().invoke(app, ["drive", str(driver), "--out", "o.mp4", "--method", "none", "--threads", "1"])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "o.mp4").is_file()


def test_bad_model_files_are_one_line_errors(driver, tmp_path):
    out = tmp_path / "out.mp4"
    cases = {
        "missing.pt": None,
        "corrupt.pt": b"\x00garbage" * 100,
    }
    for name, content in cases.items():
        path = tmp_path / name
        if content is not None:
            path.write_bytes(content)
        line = one_line_error(CliRunner().invoke(app, drive_args(driver, out, path, "--method", "none")))
        assert name in line
    foreign = tmp_path / "foreign.pt"
    torch.save({"kind": "something-else", "format_version": 1}, foreign)
    assert "not a clone2d" in one_line_error(CliRunner().invoke(app, drive_args(driver, out, foreign)))
    plain = tmp_path / "plain.pt"
    torch.save({"weight": torch.zeros(3)}, plain)
    assert "not a clone2d" in one_line_error(CliRunner().invoke(app, drive_args(driver, out, plain)))
    assert not out.exists()


def test_newer_or_damaged_model_is_refused(trained, driver, tmp_path):
    raw = torch.load(trained, map_location="cpu", weights_only=True)
    newer = tmp_path / "newer.pt"
    torch.save({**raw, "format_version": 99}, newer)
    assert "version 99" in one_line_error(CliRunner().invoke(app, drive_args(driver, tmp_path / "o.mp4", newer)))
    damaged = tmp_path / "damaged.pt"
    raw["generator"]["config"]["base_channels"] = 7
    torch.save(raw, damaged)
    line = one_line_error(CliRunner().invoke(app, drive_args(driver, tmp_path / "o.mp4", damaged)))
    assert "damaged reference model" in line


def test_bad_method_and_empty_driver(trained, tmp_path):
    drv = write_track(figure_track(10), tmp_path / "drv")
    out = tmp_path / "o.mp4"
    assert "valid: retarget, global-scale, none" in one_line_error(
        CliRunner().invoke(app, drive_args(drv, out, trained, "--method", "magic")))
    empty = tmp_path / "empty"
    empty.mkdir()
    one_line_error(CliRunner().invoke(app, drive_args(empty, out, trained, "--method", "none")))
    assert not out.exists()


def test_retarget_without_codes_or_weights_is_a_clear_error(driver, tmp_path, monkeypatch):
    monkeypatch.setattr(retarget_api, "PACKAGED_WEIGHTS", tmp_path / "not_shipped.pt")
    poses, frames = write_reference(tmp_path / "ref", figure_track(24))
    model_path = tmp_path / "ref.pt"
    assert CliRunner().invoke(app, train_args(poses, frames, model_path)).exit_code == 0
    assert load_reference_model(model_path).reference_codes is None
    line = one_line_error(CliRunner().invoke(app, drive_args(driver, tmp_path / "o.mp4", model_path)))
    assert "--weights" in line and "global-scale" in line


def test_shipped_weights_are_used_without_flags(driver, tmp_path):
    poses, frames = write_reference(tmp_path / "ref", figure_track(64))
    model_path = tmp_path / "ref.pt"
    assert CliRunner().invoke(app, train_args(poses, frames, model_path)).exit_code == 0
    model = load_reference_model(model_path)
    assert model.reference_codes is not None
    assert model.codes_weights == file_sha256(retarget_api.PACKAGED_WEIGHTS)
    result = CliRunner().invoke(app, drive_args(driver, tmp_path / "o.mp4", model_path))
    assert result.exit_code == 0, result.output
    assert len(read_video(tmp_path / "o.mp4")[0]) == 30


def test_retarget_with_weights_round_trip(tmp_path, monkeypatch):
    weights = tmp_path / "weights" / "mine.pt"  # some trained retargeting weights that are not the shipped file
    weights.parent.mkdir()
    shutil.copy(retarget_api.PACKAGED_WEIGHTS, weights)
    poses, frames = write_reference(tmp_path / "ref", figure_track(64))
    model_path = tmp_path / "ref.pt"
    args = train_args(poses, frames, model_path, "--weights", str(weights))
    assert CliRunner().invoke(app, args).exit_code == 0
    assert load_reference_model(model_path).codes_weights_path == str(weights.resolve())
    drv = write_track(figure_track(48, width=160, height=120, scale=0.7, fps=20.0), tmp_path / "drv")
    out = tmp_path / "out.mp4"
    # No --weights: the file the model's codes came from is found again (not the shipped one).
    monkeypatch.setattr(retarget_api, "PACKAGED_WEIGHTS", tmp_path / "none.pt")
    result = CliRunner().invoke(app, drive_args(drv, out, model_path, "--poses-out", str(tmp_path / "p.npz")))
    assert result.exit_code == 0, result.output
    frames_out, fps, _ = read_video(out)
    assert len(frames_out) == 48 and fps == pytest.approx(20.0)
    driven = read_track(tmp_path / "p.npz")
    model = load_reference_model(model_path)
    assert driven.image_size == model.canvas.image_size
    # The driven figure has the reference's size, not the driver's (0.7x): nearer 1 than 0.7.
    height = np.nanmedian(driven.joint("r_ankle")[:, 1] - driven.joint("neck")[:, 1])
    ref_height = np.nanmedian(model.reference_track.joint("r_ankle")[:, 1] - model.reference_track.joint("neck")[:, 1])
    assert abs(height / ref_height - 1.0) < abs(height / ref_height - 0.7)


def test_generation_is_deterministic_and_global_scale_lands_on_the_reference(trained):
    model = load_reference_model(trained)
    track = model.reference_track.frames(0, 6)
    a = [f for _, f in generate_frames(model, track, chunk=4)]
    b = [f for _, f in generate_frames(model, track, chunk=6)]
    assert len(a) == 6 and all(np.array_equal(x, y) for x, y in zip(a, b))
    # A driver that is the reference scaled by 2 comes back onto the reference.
    ref = model.reference_track
    big = ref.replace(joints=ref.joints * 2.0, image_size=(2 * ref.image_size[0], 2 * ref.image_size[1]))
    moved = move_onto_reference(big, model, "global-scale")
    np.testing.assert_allclose(moved.joints, ref.joints, atol=0.05)


@pytest.mark.parametrize("stage", ["draw", "encode"])
def test_a_failing_stage_ends_drive_with_its_error_and_leaves_nothing(trained, driver, tmp_path, monkeypatch, stage):
    """Drawing and encoding run in threads beside the generator: their errors still reach the caller, the
    unfinished video is removed and no thread is left running."""
    import clone.drive.run as drive_module
    from pose_io.video_out import VideoWriter

    calls = []

    def fail_after(original):
        def wrapped(*args, **kwargs):
            calls.append(1)
            if len(calls) > 20:
                raise OSError(f"{stage} broke")
            return original(*args, **kwargs)
        return wrapped

    if stage == "draw":
        import clone.runtime.pose_maps as generate_module

        monkeypatch.setattr(generate_module, "render_pose_map", fail_after(generate_module.render_pose_map))
    else:
        monkeypatch.setattr(VideoWriter, "write", fail_after(VideoWriter.write))
    threads = set(threading.enumerate())
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    with pytest.raises(OSError, match=f"{stage} broke"):
        drive_module.drive(driver, out_dir / "out.mp4", model_path=trained, method="none")
    assert list(out_dir.iterdir()) == []  # neither the video nor its temp file
    assert set(threading.enumerate()) <= threads


@pytest.mark.skipif(not onnx_available(), reason="needs the optional extra `fast` (onnxruntime, onnx)")
def test_onnx_runtime_makes_the_frames_torch_makes(trained):
    model = load_reference_model(trained)
    track = model.reference_track.frames(0, 8)
    torch_frames = [f for _, f in generate_frames(model, track, chunk=3, runtime="torch")]
    onnx_frames = [f for _, f in generate_frames(model, track, chunk=3, runtime="onnx")]
    assert len(onnx_frames) == 8
    for a, b in zip(torch_frames, onnx_frames):  # uint8 frames: float rounding may flip one level
        assert np.abs(a.astype(int) - b.astype(int)).max() <= 1


def test_runtime_choice(monkeypatch, trained, driver, tmp_path):
    from clone.runtime import onnx as onnx_generator

    cpu, gpu = torch.device("cpu"), torch.device("cuda")
    assert onnx_generator.generator_runtime("torch", cpu) == "torch"
    assert onnx_generator.generator_runtime("auto", gpu) == "torch"
    with pytest.raises(ValueError, match="valid: auto, torch, onnx"):
        onnx_generator.generator_runtime("tensorrt", cpu)
    monkeypatch.setattr(onnx_generator, "onnx_available", lambda: False)
    assert onnx_generator.generator_runtime("auto", cpu) == "torch"
    with pytest.raises(InputError, match=r"clone2d\[fast\]"):
        drive(driver, tmp_path / "out.mp4", model_path=trained, method="none", runtime="onnx")
    assert not (tmp_path / "out.mp4").exists()


def test_interleaved_generation_streams_leave_autograd_alone(trained):
    model = load_reference_model(trained)
    track = model.reference_track.frames(0, 5)
    streams = [generate_frames(model, track, chunk=2) for _ in range(2)]
    for a, b in zip(*streams):
        assert torch.is_grad_enabled() and not torch.is_inference_mode_enabled()
        assert np.array_equal(a[1], b[1])
    assert torch.is_grad_enabled()


def test_stage_keeps_the_driven_poses_where_the_reference_stood_unless_raw(trained, driver, tmp_path):
    # The driver's sideways sway, scaled onto the reference, is wider than the reference's own.
    model = load_reference_model(trained)
    stage = reference_stage(model.reference_track)
    runs = {}
    for mode in ("reference", "raw"):
        out, poses = tmp_path / f"{mode}.mp4", tmp_path / f"{mode}.npz"
        args = drive_args(driver, out, trained, "--method", "global-scale", "--stage", mode,
                          "--poses-out", str(poses))
        result = CliRunner().invoke(app, args)
        assert result.exit_code == 0, result.output
        assert len(read_video(out)[0]) == 30
        runs[mode] = (result.output, read_track(poses))
    (said, kept), (said_raw, raw) = runs["reference"], runs["raw"]
    assert "kept on the reference's stage" in said and "kept on" not in said_raw
    root_x = kept.joint("mid_hip")[:, 0]
    low, high = stage.x_range[0] - stage.margin, stage.x_range[1] + stage.margin
    assert low - 1e-3 <= root_x.min() and root_x.max() <= high + 1e-3
    raw_x = raw.joint("mid_hip")[:, 0]
    assert raw_x.min() < low or raw_x.max() > high  # without the stage it walks off
    # The raw poses are the library's; the kept ones are them moved by one map, with the share reported.
    driven = read_track(driver).to_layout("body15")
    np.testing.assert_allclose(raw.joints, move_onto_reference(driven, model, "global-scale", stage="raw").joints,
                               atol=1e-3)
    track, fit = drive_poses(driven, model, "global-scale", stage="reference")
    assert fit is not None and fit.moved and f"{100 * fit.share:.1f}% of frames" in said
    np.testing.assert_allclose(kept.joints, track.joints, atol=1e-3)
    assert drive_poses(driven, model, "none")[1] is None
    assert drive_poses(driven, model, "global-scale", stage="raw")[1] is None


def test_bad_stage_is_one_line_error(trained, driver, tmp_path):
    out = tmp_path / "o.mp4"
    line = one_line_error(CliRunner().invoke(app, drive_args(driver, out, trained, "--stage", "floor")))
    assert "--stage" in line and "valid: frame, reference, raw" in line
    assert not out.exists()
    model = load_reference_model(trained)
    with pytest.raises(InputError, match="valid: frame, reference, raw"):
        drive_poses(read_track(driver), model, "global-scale", stage="floor")


def test_a_face_pass_changes_the_face_only_and_not_the_frames_after(trained):
    """The face pass refines the shown frame around the face; the generator goes on from its own frame, so
    every pixel away from the face is the same as without the pass."""
    from dataclasses import replace

    from clone.model.canvas import image_to_canvas
    from clone.model.face import FACE_PASS_RADII, build_face_pass, face_pass_config

    model = load_reference_model(trained)
    torch.manual_seed(0)
    net = build_face_pass()
    for p in net.parameters():
        p.data.normal_(0.0, 0.2)
    radius = 2.0
    passed = replace(model, face_pass={"config": face_pass_config().to_dict(), "state_dict": net.state_dict(),
                                       "radius": radius})
    track = model.reference_track.frames(0, 5)
    plain = [f for _, f in generate_frames(model, track, runtime="torch")]
    refined = [f for _, f in generate_frames(passed, track, runtime="torch")]
    nose = image_to_canvas(track.to_layout(model.pose_layout).joints, model.canvas)[:, 0]  # [T, 2] canvas pixels
    changed = 0
    for t, (a, b) in enumerate(zip(plain, refined)):
        differs = np.abs(a.astype(int) - b.astype(int)).max(axis=-1) > 0  # [S, S]
        ys, xs = np.nonzero(differs)
        changed += len(ys)
        half = FACE_PASS_RADII * radius + 1.5
        assert (np.abs(xs - nose[t, 0]) <= half).all() and (np.abs(ys - nose[t, 1]) <= half).all()
    assert changed > 0


def test_codes_stored_with_another_view_pooling_are_computed_again(tmp_path, monkeypatch):
    """Models trained before the 'facing' view pool store codes without saying how they were pooled: driving
    them computes the codes again from the stored track, as it does for other weights."""
    from dataclasses import replace

    from clone.drive.poses import retarget_onto

    poses, frames = write_reference(tmp_path / "ref", figure_track(64))
    model_path = tmp_path / "ref.pt"
    assert CliRunner().invoke(app, train_args(poses, frames, model_path)).exit_code == 0
    model = load_reference_model(model_path)
    assert model.reference_codes["view_pool"] == "facing"
    driver = figure_track(40)
    computed = []
    from retarget.inference.algorithm import RetargeterBase

    original = RetargeterBase.reference_codes

    def counting(self, *args, **kwargs):
        computed.append(1)
        return original(self, *args, **kwargs)

    monkeypatch.setattr(RetargeterBase, "reference_codes", counting)
    same = retarget_onto(driver, model, None)
    assert not computed  # stored codes pooled as today's: used as they are
    old = replace(model, reference_codes={k: v for k, v in model.reference_codes.items() if k != "view_pool"})
    again = retarget_onto(driver, old, None)
    assert computed  # recomputed; on this figure (never turning) to the same poses
    np.testing.assert_allclose(again.joints, same.joints, atol=1e-3)
