"""Stage `drive`: ``clone.drive.drive`` end to end (pose file -> H.264 mp4), frames/s and peak RSS.

A tiny reference model is trained for a few steps in a temporary folder on a short synthetic performance
(motion world, 24 frames) at a 64² canvas: speed does not depend on how well it is trained, but it does
on the canvas (the generator's cost grows with its area). Each (track length, method) runs in its own
subprocess (``python -m bench.drive``) so its peak RSS is its own; 1,000 vs 10,000 frames shows whether
memory stays flat. Baseline, measured in the same subprocess: the generator alone, batch 1 under
inference mode at the same canvas, frame after frame (the floor drive cannot beat on this path).
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


def make_model(folder: Path) -> Path:
    """Train a reference model a few steps on a 24-frame synthetic performance; returns its path."""
    from clone.demo import demo_motions
    from clone.synth import get_character, save_performance
    from clone.train_ref import TrainConfig, train_reference

    skeleton, look, _ = get_character("tall_long_legs")
    ref = save_performance(folder / "reference", demo_motions()["reference"], skeleton, look, yaw=15.0,
                           size=128, frames=24)
    out = folder / "ref_model.pt"
    train_reference(ref / "poses.npz", ref / "frames", out, config=TrainConfig(size=CANVAS), steps=3)
    return out


def child(args: dict[str, Any]) -> dict[str, Any]:
    import torch

    from bench.harness import peak_rss_mb, time_call
    from clone.drive import drive
    from clone.networks import generator_input
    from clone.reference_model import load_reference_model

    torch.set_num_threads(1)
    t0 = time.perf_counter()
    result = drive(args["driver"], args["out"], model_path=args["model"], method=args["method"], device="cpu",
                   overwrite=True)
    seconds = time.perf_counter() - t0
    peak = peak_rss_mb()
    model = load_reference_model(args["model"])
    net = model.build_generator("cpu")
    size = model.canvas.size
    pose, prev = torch.zeros(1, 3, size, size), torch.zeros(1, 3, size, size)

    def generator_only() -> None:
        with torch.inference_mode():
            for _ in range(50):
                net(generator_input(pose, prev))

    gen = time_call(generator_only, 5, 1)
    return {"frames": result.frames, "seconds": seconds, "fps": result.frames / seconds, "peak_rss_mb": peak,
            "generator_fps": gen.rate(50), "canvas": size, "mp4_bytes": Path(args["out"]).stat().st_size}


def run(quick: bool = False, **_: object) -> dict[str, Any]:
    from bench.data import source_track, tiled
    from bench.harness import row, run_child
    from pose_io.writers import write_track

    tmp = Path(tempfile.mkdtemp(prefix="bench_drive_"))
    try:
        t0 = time.perf_counter()
        model = make_model(tmp)
        train_s = time.perf_counter() - t0
        source, origin = source_track()
        rows = []
        for frames in (300, 1_000) if quick else (1_000, 10_000):
            driver = write_track(tiled(source, frames), tmp / f"driver_{frames}.npz")
            for method in METHODS:
                r = run_child("bench.drive", {"driver": str(driver), "out": str(tmp / f"out_{frames}_{method}.mp4"),
                                              "model": str(model), "method": method})
                rows.append(row(f"{frames:,} frames, {CANVAS}² canvas", f"drive --method {method}", r["fps"],
                                "frames/s", r["generator_fps"], "generator alone (inference mode, batch 1)",
                                peak_rss_mb=round(r["peak_rss_mb"], 1), seconds=round(r["seconds"], 2)))
        return {
            "rows": rows,
            "notes": [
                (f"driver: {origin}, tiled forwards-backwards; model: TrainConfig(size={CANVAS}) trained 3 steps on a "
                f"24-frame synthetic performance in a temp dir ({train_s:.0f} s); 1 thread; one subprocess each"),
                ("frames/s counts the whole call (load model, read + fill track, move poses, draw, generate, encode); "
                "peak_rss_mb is the subprocess's VmHWM"),
            ],
        }
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    print(json.dumps(child(json.loads(sys.argv[1]))))
