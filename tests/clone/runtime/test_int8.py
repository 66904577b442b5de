"""clone.runtime.int8: the generator quantised to int8 on ONNX Runtime; close to fp32, cached, never fatal."""

from __future__ import annotations

import hashlib
import logging
import os
import tempfile
from dataclasses import replace

import numpy as np
import pytest
import torch
from typer.testing import CliRunner

from clone.cli.main import app
from clone.model.canvas import full_frame_canvas
from clone.model.networks import build_generator, generator_input
from clone.model.reference import ReferenceModel, save_reference_model
from clone.model.tensors import to_tensor
from clone.runtime import int8 as int8_generator
from clone.runtime.generate import build_drive_generator
from clone.runtime.int8 import QuantConfig, build_int8_generator, cache_key, read_cached
from clone.runtime.onnx import OnnxGenerator, generator_runtime
from clone.runtime.pose_maps import draw_pose_maps
from clone.train_ref import TrainConfig
from pose_io.writers import write_track
from tests.clone.train_ref.helpers import figure_track, one_line_error

pytest.importorskip("onnxruntime")
onnx = pytest.importorskip("onnx")

SIZE = 64
FAST = QuantConfig(frames=8)  # fewer calibration frames keep each build well under a second


@pytest.fixture(scope="module")
def model() -> ReferenceModel:
    """A 64² model with the default generator for its size (alpha over a plate), random weights."""
    torch.manual_seed(0)
    config = TrainConfig(size=SIZE).generator_config()
    track = figure_track(24)
    rng = np.random.default_rng(0)
    return ReferenceModel(
        generator_name="unet", generator_config=config, generator_state=build_generator("unet", config).state_dict(),
        canvas=full_frame_canvas(track.image_size, SIZE), scale_stats=None, reference_track=track, track_summary={},
        plate=rng.integers(0, 256, (SIZE, SIZE, 3), dtype=np.uint8),
    )


def rollout(generator, model: ReferenceModel, frames: int = 8) -> np.ndarray:
    """[N, 3, S, S] frames in [-1, 1], each made from the one before (as clone drive runs)."""
    pose = to_tensor(np.concatenate(list(draw_pose_maps(model, model.reference_track.frames(0, frames)))))
    plate, prev, out = model.plate_tensor(), torch.zeros(1, 3, SIZE, SIZE), []
    with torch.inference_mode():
        for i in range(frames):
            prev = generator(generator_input(pose[i:i + 1], prev), plate)  # [1, 3, S, S]
            out.append(prev.numpy()[0])
    return np.stack(out)


def quantised(generator: OnnxGenerator) -> bool:
    ops = {node.op_type for node in onnx.load_from_string(generator.onnx).graph.node}
    return generator.precision == "int8" and {"QuantizeLinear", "DequantizeLinear"} <= ops


def test_int8_frames_are_close_to_fp32(model, tmp_path):
    int8 = build_int8_generator(model, threads=1, cache_dir=tmp_path, config=FAST)
    assert quantised(int8)
    fp32 = OnnxGenerator(model.build_generator(), SIZE, with_plate=True, threads=1)
    a, b = rollout(int8, model), rollout(fp32, model)
    diff = np.abs(a - b).mean()
    # The frames are mostly the plate (alpha compositing): int8 must also keep what the network adds to it.
    added = np.abs(b - model.plate_tensor().numpy()).mean()
    assert 0 < diff < 0.05 and diff < 0.25 * added


def test_second_build_reuses_the_cache_and_leaves_no_temp_files(model, tmp_path, monkeypatch):
    temp = tmp_path / "temp"
    temp.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(temp))  # where quantize_static and we put temp files
    cache = tmp_path / "cache"
    build_int8_generator(model, threads=1, cache_dir=cache, config=FAST)
    [entry] = cache.iterdir()
    assert entry.name == f"{cache_key(model, FAST)}.int8.onnx" and list(temp.iterdir()) == []
    stamp, content = entry.stat(), entry.read_bytes()
    os.utime(entry, ns=(stamp.st_atime_ns, stamp.st_mtime_ns - 10**9))  # used a second ago

    def no_quantising(*args, **kwargs):
        raise AssertionError("quantised again")

    monkeypatch.setattr(int8_generator, "quantize", no_quantising)
    again = build_int8_generator(model, threads=1, cache_dir=cache, config=FAST)
    assert quantised(again) and list(cache.iterdir()) == [entry] and entry.read_bytes() == content
    assert entry.stat().st_ino == stamp.st_ino and entry.stat().st_mtime_ns > stamp.st_mtime_ns - 10**9  # marked used


def test_the_cache_keeps_the_most_recently_used_models_within_its_budget(tmp_path):
    for age, name in enumerate(("new", "mid", "old", "oldest")):
        path = tmp_path / f"{name}.int8.onnx"
        path.write_bytes(bytes(100))
        os.utime(path, ns=(0, 10**12 - age * 10**9))
    other = tmp_path / "notes.txt"
    other.write_bytes(bytes(1000))
    keep = tmp_path / "oldest.int8.onnx"  # the one just written stays even though it is the oldest here
    deleted = int8_generator.prune_cache(tmp_path, keep, max_bytes=250)
    assert sorted(p.name for p in deleted) == ["mid.int8.onnx", "old.int8.onnx"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["new.int8.onnx", "notes.txt", "oldest.int8.onnx"]
    assert int8_generator.prune_cache(tmp_path, keep, max_bytes=250) == []  # within budget now


def test_writing_a_model_prunes_the_cache(model, tmp_path, monkeypatch):
    cache = tmp_path / "cache"
    cache.mkdir()
    stale = cache / "stale.int8.onnx"
    stale.write_bytes(bytes(10))
    os.utime(stale, ns=(0, 0))
    monkeypatch.setattr(int8_generator, "MAX_CACHE_BYTES", 1)
    build_int8_generator(model, threads=1, cache_dir=cache, config=FAST)
    assert [p.name for p in cache.iterdir()] == [f"{cache_key(model, FAST)}.int8.onnx"]


def test_the_key_follows_what_decides_the_result(model):
    key = cache_key(model, FAST)
    state = {k: v.clone() for k, v in model.generator_state.items()}
    next(v for v in state.values() if v.is_floating_point()).view(-1)[0] += 1e-3
    plate = model.plate.copy()
    plate[0, 0, 0] ^= 1
    track = model.reference_track
    moved = track.replace(joints=track.joints + np.float32(0.5))
    others = [cache_key(replace(model, **change), FAST)
              for change in ({"generator_state": state}, {"plate": plate}, {"reference_track": moved})]
    others.append(cache_key(model, QuantConfig(frames=9)))
    assert len({key, *others}) == 5
    same = {k: v.clone() for k, v in model.generator_state.items()}  # equal tensors, other objects
    assert cache_key(replace(model, generator_state=same, plate=model.plate.copy()), FAST) == key


@pytest.mark.parametrize("damage", ["flip_a_byte", "truncate", "not_onnx"])
def test_a_damaged_cache_file_is_rebuilt(model, tmp_path, caplog, damage):
    build_int8_generator(model, threads=1, cache_dir=tmp_path, config=FAST)
    [entry] = tmp_path.iterdir()
    data = bytearray(entry.read_bytes())
    if damage == "flip_a_byte":
        data[len(data) // 2] ^= 0xFF
    elif damage == "truncate":
        data = data[: len(data) // 3]
    else:  # a file whose checksum is right but whose content is no model
        payload = b"not an onnx model"
        data = bytearray(int8_generator.MAGIC + hashlib.sha256(payload).digest() + payload)
    entry.write_bytes(bytes(data))
    with caplog.at_level(logging.WARNING, logger="clone.runtime.int8"):
        rebuilt = build_int8_generator(model, threads=1, cache_dir=tmp_path, config=FAST)
    assert quantised(rebuilt)
    assert any("rebuilding" in r.getMessage() for r in caplog.records)
    assert read_cached(entry) == rebuilt.onnx  # the file was written again, whole


def test_failed_quantisation_falls_back_to_fp32(model, tmp_path, caplog, monkeypatch):
    def broken(*args, **kwargs):
        raise RuntimeError("no kernel for this op")

    monkeypatch.setattr(int8_generator, "quantize", broken)
    with caplog.at_level(logging.WARNING, logger="clone.runtime.int8"):
        generator = build_int8_generator(model, threads=1, cache_dir=tmp_path, config=FAST)
    assert generator.precision == "fp32" and list(tmp_path.iterdir()) == []
    assert any("no kernel for this op" in r.getMessage() for r in caplog.records)
    with torch.no_grad():
        expected = rollout(model.build_generator(), model, 3)
    np.testing.assert_allclose(rollout(generator, model, 3), expected, atol=1e-5)


def test_a_signal_inside_quantisation_stops_the_command_instead_of_falling_back(model, tmp_path, monkeypatch):
    def interrupted(*args, **kwargs):
        try:
            raise SystemExit(143)  # the SIGTERM handler, as if the signal arrived inside onnxruntime
        except SystemExit as stop:
            raise ImportError("initialization failed") from stop  # what the extension makes of it

    monkeypatch.setattr(int8_generator, "quantize", interrupted)
    with pytest.raises(SystemExit) as ended:
        build_int8_generator(model, threads=1, cache_dir=tmp_path, config=FAST)
    assert ended.value.code == 143 and list(tmp_path.iterdir()) == []


def test_int8_frames_far_from_fp32_fall_back_to_fp32(model, tmp_path, caplog):
    with caplog.at_level(logging.WARNING, logger="clone.runtime.int8"):
        generator = build_int8_generator(model, threads=1, cache_dir=tmp_path,
                                         config=QuantConfig(frames=8, max_mean_abs_diff=0.0))
    assert generator.precision == "fp32" and list(tmp_path.iterdir()) == []
    assert any("differ from fp32" in r.getMessage() for r in caplog.records)


def test_a_nearly_full_disk_or_unwritable_cache_skips_caching(model, tmp_path, caplog, monkeypatch):
    real = int8_generator.shutil.disk_usage
    monkeypatch.setattr(int8_generator.shutil, "disk_usage", lambda p: real(p)._replace(free=1000))
    with caplog.at_level(logging.WARNING, logger="clone.runtime.int8"):
        generator = build_int8_generator(model, threads=1, cache_dir=tmp_path / "full", config=FAST)
    assert quantised(generator) and list((tmp_path / "full").iterdir()) == []
    assert any("not caching" in r.getMessage() for r in caplog.records)
    monkeypatch.undo()
    blocked = tmp_path / "file"
    blocked.write_text("a file where the folder should be")
    assert quantised(build_int8_generator(model, threads=1, cache_dir=blocked / "cache", config=FAST))


def test_auto_picks_int8_on_a_cpu_with_the_extra(model, monkeypatch):
    from clone.runtime import onnx as onnx_generator

    cpu = torch.device("cpu")
    assert generator_runtime("auto", cpu) == "int8" and generator_runtime("int8", cpu) == "int8"
    assert generator_runtime("auto", torch.device("cuda")) == "torch"
    with pytest.raises(ValueError, match="int8 runtime runs on the CPU"):
        generator_runtime("int8", torch.device("cuda"))
    assert quantised(build_drive_generator(model, cpu, "auto"))  # cached in the conftest's folder
    monkeypatch.setattr(onnx_generator, "onnx_available", lambda: False)
    assert generator_runtime("auto", cpu) == "torch"
    with pytest.raises(ValueError, match=r"clone2d\[fast\]"):
        generator_runtime("int8", cpu)


def test_cli_runtime_option(model, tmp_path):
    path = save_reference_model(model, tmp_path / "ref.pt")
    driver = figure_track(6, width=160, height=120, scale=0.7)
    poses = write_track(driver, tmp_path / "driver.npz")
    args = ["drive", str(poses), "--model", str(path), "--method", "none", "--threads", "1", "--device", "cpu"]
    runner = CliRunner()
    for runtime in ("int8", "onnx"):
        result = runner.invoke(app, [*args, "--out", str(tmp_path / f"{runtime}.mp4"), "--runtime", runtime])
        assert result.exit_code == 0, result.output
        assert os.path.getsize(tmp_path / f"{runtime}.mp4") > 0
    line = one_line_error(runner.invoke(app, [*args, "--out", str(tmp_path / "x.mp4"), "--runtime", "tensorrt"]))
    assert "valid: auto, torch, onnx, int8" in line and not (tmp_path / "x.mp4").exists()


def test_a_generator_without_previous_frame_or_plate_quantises_too(model, tmp_path):
    torch.manual_seed(0)
    config = replace(model.generator_config, in_channels=3, alpha=False)
    plain = replace(model, generator_config=config, generator_state=build_generator("unet", config).state_dict(),
                    temporal=False, plate=None)
    int8 = build_int8_generator(plain, threads=1, cache_dir=tmp_path, config=FAST)
    assert quantised(int8) and not int8.with_plate
    pose = to_tensor(next(draw_pose_maps(plain, plain.reference_track.frames(0, 2))))  # [2, 3, S, S]
    with torch.no_grad():
        expected = plain.build_generator()(pose)
    assert np.abs(int8(pose).numpy() - expected.numpy()).mean() < 0.05


@pytest.mark.prepare_drive
def test_train_ref_leaves_the_int8_generator_in_the_cache(tmp_path):
    pytest.importorskip("onnxruntime")
    from clone.model.reference import load_reference_model
    from tests.clone.train_ref.helpers import figure_track, train_args, write_reference

    poses, frames = write_reference(tmp_path / "ref", figure_track(12))
    out = tmp_path / "ref.pt"
    run = CliRunner().invoke(app, train_args(poses, frames, out, steps=2))
    assert run.exit_code == 0, run.output
    assert "int8 generator for clone drive cached" in run.output
    model = load_reference_model(out)
    cached = int8_generator.generator_cache_dir() / f"{cache_key(model, QuantConfig())}.int8.onnx"
    assert read_cached(cached) is not None  # the first drive finds it
