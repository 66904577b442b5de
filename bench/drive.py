"""Stage `drive`: ``clone.drive.run.drive`` end to end (pose file -> H.264 mp4), frames/s and peak RSS.

Tiny reference models are trained for a few steps in a temporary folder on a short synthetic performance
(motion world, 24 frames): speed does not depend on how well a model is trained, but it does on the canvas
and the generator's shape. Each (track length, method, model) runs in its own subprocess (``python -m
bench.drive``) so its peak RSS is its own.

- 64² canvas, 1,000 vs 10,000 frames: whether memory stays flat. Baseline, measured in the same subprocess:
  the generator alone on drive's runtime, batch 1, frame after frame (the floor drive cannot beat).
- 256² canvas (issue #12: 25 frames/s on a laptop CPU): the whole command with today's default generator
  against the same command with the old default (``base_channels`` 32) in the same run; and the two
  generators alone. With the ``fast`` extra, also on ONNX Runtime in fp32 and in int8 (first drive, which
  quantises, then a second one that reads the quantised model from the cache), with the SSIM of the int8
  frames against the fp32 session's.
"""

from __future__ import annotations

import json
import shutil
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

CANVAS = 64
METHODS = ("global-scale", "retarget")
LARGE = 256  # the canvas of issue #12's drive rows
# TrainConfig fields of the 256² default generator before issue #12 (the same-run baseline of the 256² rows).
OLD_DEFAULT = {"base_channels": 32}


def make_model(folder: Path, size: int = CANVAS, steps: int = 3, **config: Any) -> Path:
    """Train a reference model a few steps on a 24-frame synthetic performance; returns its path.

    Args:
        folder: where the performance and the model go.
        size: canvas size.
        steps: training steps.
        **config: TrainConfig fields other than ``size``.
    """
    from clone.demo import demo_motions
    from clone.synth import get_character, save_performance
    from clone.train_ref import TrainConfig, train_reference

    render = max(128, size)
    ref = folder / f"reference_{render}"
    if not ref.is_dir():
        skeleton, look, _ = get_character("tall_long_legs")
        save_performance(ref, demo_motions()["reference"], skeleton, look, yaw=15.0, size=render, frames=24)
    out = folder / f"ref_model_{size}_{len(list(folder.glob('ref_model_*.pt')))}.pt"
    train_reference(ref / "poses.npz", ref / "frames", out, config=TrainConfig(size=size, **config), steps=steps)
    return out


def child(args: dict[str, Any]) -> dict[str, Any]:
    import torch

    from bench.harness import peak_rss_mb, time_call
    from clone.drive.run import drive
    from clone.model.networks import generator_input
    from clone.model.reference import load_reference_model
    from clone.runtime.generate import build_drive_generator

    torch.set_num_threads(1)
    runtime = args.get("runtime", "auto")
    if "int8_cache" in args:  # a cache of this run's own, so that "first" and "cached" mean what they say
        from clone.runtime import int8 as int8_generator

        int8_generator.generator_cache_dir = lambda: Path(args["int8_cache"])
    t0 = time.perf_counter()
    result = drive(args["driver"], args["out"], model_path=args["model"], method=args["method"], device="cpu",
                   overwrite=True, runtime=runtime)
    seconds = time.perf_counter() - t0
    peak = peak_rss_mb()
    model = load_reference_model(args["model"])
    net = build_drive_generator(model, torch.device("cpu"), runtime)  # what drive ran
    size = model.canvas.size
    pose, prev = torch.zeros(1, 3, size, size), torch.zeros(1, 3, size, size)
    exemplar = torch.zeros(1, 3, size, size) if model.sees_exemplar else None
    plate = model.plate_tensor("cpu")  # [1, 3, S, S], None for a model trained without one

    def generator_only() -> None:
        with torch.inference_mode():
            for _ in range(50):
                net(generator_input(pose, prev, exemplar), plate)

    gen = time_call(generator_only, 5, 1)
    out = {"frames": result.frames, "seconds": seconds, "fps": result.frames / seconds, "peak_rss_mb": peak,
           "generator_fps": gen.rate(50), "canvas": size, "mp4_bytes": Path(args["out"]).stat().st_size,
           "base_channels": model.generator_config.base_channels, "precision": getattr(net, "precision", "fp32")}
    if runtime == "int8":
        out["ssim_vs_fp32"] = int8_ssim(model, args["driver"], args["method"])
    return out


def int8_ssim(model: Any, driver_path: str, method: str, frames: int = 60) -> float:
    """Mean SSIM of the int8 generator's frames against the fp32 ONNX session's over the first driven frames
    (each runtime on its own previous frames, as when driving)."""
    from clone.drive.poses import drive_poses, read_driver
    from clone.metrics.frames import frame_pair_scores
    from clone.runtime.generate import generate_frames

    driven, _ = drive_poses(read_driver(driver_path, layout=model.pose_layout), model, method)
    track = driven.frames(0, min(frames, driven.num_frames))
    int8 = [frame for _, frame in generate_frames(model, track, runtime="int8")]
    fp32 = [frame for _, frame in generate_frames(model, track, runtime="onnx")]
    return float(sum(frame_pair_scores(a, b)[0] for a, b in zip(int8, fp32)) / len(int8))


def run(quick: bool = False, **_: object) -> dict[str, Any]:
    from bench.data import source_track, tiled
    from bench.harness import row, run_child
    from pose_io.writers import write_track

    tmp = Path(tempfile.mkdtemp(prefix="bench_drive_"))
    try:
        t0 = time.perf_counter()
        model = make_model(tmp)
        train_s = time.perf_counter() - t0
        cache = tmp / "int8_cache"  # this run's own, never the user's
        prepared = prepare_int8(model, cache)
        source, origin = source_track()
        rows = []
        for frames in (300, 1_000) if quick else (1_000, 10_000):
            driver = write_track(tiled(source, frames), tmp / f"driver_{frames}.npz")
            for method in METHODS:
                r = run_child("bench.drive", {"driver": str(driver), "out": str(tmp / f"out_{frames}_{method}.mp4"),
                                              "model": str(model), "method": method, "int8_cache": str(cache)})
                rows.append(row(f"{frames:,} frames, {CANVAS}² canvas", f"drive --method {method}", r["fps"],
                                "frames/s", r["generator_fps"], "generator alone (drive's runtime, batch 1)",
                                peak_rss_mb=round(r["peak_rss_mb"], 1), seconds=round(r["seconds"], 2)))
        rows += large_rows(tmp, source, 100 if quick else 300)
        return {
            "rows": rows,
            "notes": [
                (f"driver: {origin}, tiled forwards-backwards; model: TrainConfig(size={CANVAS}) trained 3 steps on a "
                f"24-frame synthetic performance in a temp dir ({train_s:.0f} s); 1 thread; one subprocess each"),
                ("frames/s counts the whole call (load model, read + fill track, move poses, draw, generate, encode); "
                "peak_rss_mb is the subprocess's VmHWM"),
                (f"{CANVAS}² rows: drive's default runtime ({prepared}); an int8 model is quantised once before "
                "them, so they drive it from the cache as every drive after the first does"),
                (f"{LARGE}² rows: TrainConfig(size={LARGE}) (today's default) against TrainConfig(size={LARGE}, "
                f"**{OLD_DEFAULT}) (the old default) on torch, each trained 1 step, driven with --method "
                "global-scale; the generator on 1 thread (torch or ONNX Runtime), drawing and encoding in drive's "
                "own threads, x264 in its own process; 'generator alone' runs the same runtime, batch 1"),
                (f"{LARGE}² int8 rows: 'first drive' quantises (calibration rollout, export, quantisation; in "
                "its seconds), 'cached' is the next drive of the same model; ssim_vs_fp32: int8 frames against the "
                "fp32 session's over 60 driven frames, on a model trained 1 step (its frames are mostly the plate, "
                "so this says little: the quality cost on a trained model is in the README)"),
            ],
        }
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def prepare_int8(model_path: Path, cache: Path) -> str:
    """Quantise the model into ``cache`` when drive's default runtime is int8; returns that runtime's name."""
    import torch

    from clone.model.reference import load_reference_model
    from clone.runtime.int8 import build_int8_generator
    from clone.runtime.onnx import generator_runtime

    runtime = generator_runtime("auto", torch.device("cpu"))
    if runtime == "int8":
        runtime = build_int8_generator(load_reference_model(model_path), threads=1, cache_dir=cache).precision
    return runtime


def large_rows(tmp: Path, source: Any, frames: int) -> list[dict[str, Any]]:
    """Issue #12's rows: drive at 256², whole command and generator alone, today's default vs the old one."""
    from bench.data import tiled
    from bench.harness import row, run_child
    from pose_io.writers import write_track

    driver = write_track(tiled(source, frames), tmp / f"driver_large_{frames}.npz")
    from clone.runtime.onnx import onnx_available

    models = {"default": make_model(tmp, LARGE, steps=1), "old": make_model(tmp, LARGE, steps=1, **OLD_DEFAULT)}
    # The baseline is the state before issue #12: the old default generator on torch. (run label, model, runtime)
    runs = [("old", "old", "torch"), ("torch", "default", "torch")]
    if onnx_available():
        # int8 twice on one fresh cache: the first drive quantises, the second reads the cache.
        runs += [("onnx", "default", "onnx"), ("int8, first drive", "default", "int8"),
                 ("int8, cached", "default", "int8")]
    results = {}
    for label, name, runtime in runs:
        results[label] = run_child("bench.drive", {
            "driver": str(driver), "out": str(tmp / f"out_large_{name}_{runtime}.mp4"), "model": str(models[name]),
            "method": "global-scale", "runtime": runtime, "int8_cache": str(tmp / "int8_cache")})
    old = results["old"]
    old_name = "old default (" + ", ".join(f"{k} {v}" for k, v in OLD_DEFAULT.items()) + "), torch"
    rows = []
    for label, _, runtime in runs[1:]:
        r = results[label]
        variant = f"default (base_channels {r['base_channels']}), {label}"
        if r["precision"] != ("int8" if runtime == "int8" else "fp32"):
            variant += f" (ran in {r['precision']})"  # int8 fell back to fp32
        quality = {"ssim_vs_fp32": round(r["ssim_vs_fp32"], 4)} if "ssim_vs_fp32" in r else {}
        rows.append(row(f"{frames:,} frames, {LARGE}² canvas", f"drive, {variant}", r["fps"], "frames/s", old["fps"],
                        f"drive, {old_name}", peak_rss_mb=round(r["peak_rss_mb"], 1), seconds=round(r["seconds"], 2),
                        **quality))
        if label != "int8, first drive":  # the same generator as the cached run
            rows.append(row(f"generator alone, {LARGE}², 1 thread", variant.replace(", cached", ""),
                            r["generator_fps"], "frames/s", old["generator_fps"], old_name))
    return rows


if __name__ == "__main__":
    print(json.dumps(child(json.loads(sys.argv[1]))))
