"""Stage `gpu`: training steps/s and drive-path generator frames/s on a CUDA GPU, when there is one.

Training: ``clone.train_ref.Trainer.train_step`` on random batches at 128² (default TrainConfig), batch 1.
Generation: the generator under inference mode at 128², batch 1, frame by frame as ``clone drive`` runs it.
Baseline: the same on the CPU, 1 thread, in the same run.
"""

from __future__ import annotations

from typing import Any


def _rates(device: Any, quick: bool) -> tuple[float, float]:
    import torch

    from bench.harness import time_call
    from clone.model.networks import generator_input
    from clone.train_ref import TrainConfig, Trainer

    config = TrainConfig(size=128)
    trainer = Trainer(config, device)
    s = config.size
    sample = {k: torch.rand(1, 3, s, s, device=device) * 2 - 1
              for k in ("pose_prev", "pose_cur", "frame_prev", "frame_cur", "plate")}  # each [1, 3, S, S]
    sample["has_prev"] = torch.ones(1, dtype=torch.bool, device=device)
    gen = torch.Generator().manual_seed(0)
    sync = torch.cuda.synchronize if device.type == "cuda" else (lambda: None)

    def step() -> None:
        trainer.train_step(sample, *trainer.previous_input(sample, gen))
        sync()

    def frames() -> None:
        with torch.inference_mode():
            for _ in range(10):
                trainer.g(generator_input(sample["pose_cur"], sample["frame_prev"]), sample["plate"])
        sync()

    reps = 3 if quick else 5
    return time_call(step, reps, 2).rate(1), time_call(frames, reps, 2).rate(10)


def run(quick: bool = False, **_: object) -> dict[str, Any]:
    import torch

    from bench.harness import row

    if not torch.cuda.is_available():
        return {"rows": [], "notes": ["no GPU in this run (torch.cuda.is_available() is False)"]}
    torch.set_num_threads(1)
    cpu_train, cpu_gen = _rates(torch.device("cpu"), quick)
    dev = torch.device("cuda")
    gpu_train, gpu_gen = _rates(dev, quick)
    name = torch.cuda.get_device_name(dev)
    return {
        "rows": [
            row("train step, 128², batch 1", f"cuda ({name})", gpu_train, "steps/s", cpu_train, "cpu, 1 thread"),
            row("generator, 128², batch 1", f"cuda ({name})", gpu_gen, "frames/s", cpu_gen, "cpu, 1 thread"),
        ],
        "notes": [f"device: {name}"],
    }
