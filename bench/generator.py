"""Stage `generator`: the U-Net generator (default ``TrainConfig`` generator) at 128² and 256², 1 and 2 threads.

Every (size, threads, option) runs in its own fresh subprocess (``python -m bench.generator``), so its
peak RSS (``VmHWM``) is that configuration's alone; ``rss_delta_mb`` is the peak minus the RSS after
importing torch and building the model and input, i.e. what running the option costs. Batch 1, frame by
frame, as ``clone.runtime.generate.generate_frames`` runs a temporal generator.

Baseline: eager fp32 with autograd on (eval mode). Options: ``inference_mode`` (what clone/drive/run.py uses
today), ``channels_last`` (+ inference mode), ``bf16_autocast`` (CPU autocast + inference mode),
``jit_trace_freeze`` (``torch.jit.freeze(torch.jit.trace(...))`` under no_grad), ``compile``
(``torch.compile`` default mode, inference mode; its compile time is recorded), ``onnxruntime`` (the
generator exported to ONNX and run by ONNX Runtime in fp32; the export is ``prepare_s``), ``int8`` (the same
export statically quantised by :mod:`clone.runtime.int8`, what ``clone drive`` uses on a CPU when the ``fast``
extra is installed; calibrated here on 8 random inputs, as the network is untrained; export + quantisation is
``prepare_s``). ``max_abs_diff`` / ``mean_abs_diff`` are each option's largest / mean output difference from
fp32 eager on the same input (outputs are in [-1, 1]).
"""

from __future__ import annotations

import contextlib
import json
import sys
import time
from typing import Any

OPTIONS = ("eager_grad", "inference_mode", "channels_last", "bf16_autocast", "jit_trace_freeze", "compile",
           "onnxruntime", "int8")
ONNX_OPTIONS = ("onnxruntime", "int8")  # need the `fast` extra
BASELINE = "eager_grad"


def _runner(option: str, net: Any, x: Any, plate: Any = None) -> tuple[Any, float]:
    """(zero-argument call producing [1, 3, S, S], seconds spent preparing / compiling).

    ``plate`` ([1, 3, S, S] or None) is passed to every call: a generator with a background plate needs it.
    """
    import torch

    t0 = time.perf_counter()
    if option == "eager_grad":
        def call() -> Any:
            with torch.enable_grad():
                return net(x, plate)
    elif option == "inference_mode":
        def call() -> Any:
            with torch.inference_mode():
                return net(x, plate)
    elif option == "channels_last":
        net = net.to(memory_format=torch.channels_last)
        xc = x.contiguous(memory_format=torch.channels_last)

        def call() -> Any:
            with torch.inference_mode():
                return net(xc, plate)
    elif option == "bf16_autocast":
        def call() -> Any:
            with torch.inference_mode(), torch.autocast("cpu", dtype=torch.bfloat16):
                return net(x, plate)
    elif option == "jit_trace_freeze":
        with torch.no_grad():
            traced = torch.jit.freeze(torch.jit.trace(net, (x, plate) if plate is not None else x))

        def call() -> Any:
            with torch.no_grad():
                return traced(x, plate) if plate is not None else traced(x)
    elif option == "compile":
        compiled = torch.compile(net)
        with torch.inference_mode():
            compiled(x, plate)  # compiles

        def call() -> Any:
            with torch.inference_mode():
                return compiled(x, plate)
    elif option == "onnxruntime":
        from clone.runtime.onnx import OnnxGenerator

        session = OnnxGenerator(net, x.shape[-1], plate is not None, threads=torch.get_num_threads())

        def call() -> Any:
            return session(x, plate)
    elif option == "int8":
        from clone.runtime.int8 import QuantConfig, quantize
        from clone.runtime.onnx import OnnxGenerator, export_onnx

        generator = torch.Generator().manual_seed(1)
        feeds = [{"x": (torch.rand(x.shape, generator=generator) * 2 - 1).numpy(),
                  **({"plate": plate.numpy()} if plate is not None else {})} for _ in range(8)]
        model = quantize(export_onnx(net, x.shape[-1], plate is not None), feeds, QuantConfig())
        session = OnnxGenerator.from_onnx(model, plate is not None, torch.get_num_threads(), "int8")

        def call() -> Any:
            return session(x, plate)
    else:
        raise ValueError(f"unknown option {option!r}; valid: {', '.join(OPTIONS)}")
    return call, time.perf_counter() - t0


def child(args: dict[str, Any]) -> dict[str, Any]:
    """One configuration in this (fresh) process: frames/s, peak RSS, output difference from fp32 eager."""
    import torch

    from bench.harness import peak_rss_mb, rss_mb, time_call
    from clone.model.networks import UNetGenerator
    from clone.train_ref import TrainConfig

    size, threads, option = int(args["size"]), int(args["threads"]), str(args["option"])
    torch.set_num_threads(threads)
    torch.manual_seed(0)
    config = TrainConfig(size=size).generator_config()
    net = UNetGenerator(config).eval()
    x = torch.rand(1, config.in_channels, size, size) * 2 - 1  # [1, 6, S, S]
    plate = torch.rand(1, 3, size, size) * 2 - 1 if config.uses_plate else None  # [1, 3, S, S]
    rss_before = rss_mb()
    call, prepare_s = _runner(option, net, x, plate)
    t0 = time.perf_counter()
    call()  # first warm-up call; a slow option (seconds per frame) gets no further warm-up and 3 samples
    slow = time.perf_counter() - t0 > 1.0
    repeats = 3 if slow else int(args["repeats"])
    timing = time_call(call, repeats, 0 if slow else 1, 0.0 if slow else float(args["min_time_s"]))
    peak = peak_rss_mb()
    with torch.no_grad():
        ref = UNetGenerator(config).eval()
        ref.load_state_dict({k: v.contiguous() for k, v in net.state_dict().items()})
        diff = (call().float().contiguous() - ref(x, plate)).abs()  # [1, 3, S, S]
    return {"fps": timing.rate(1), "median_s": timing.median_s, "peak_rss_mb": peak, "rss_before_mb": rss_before,
            "rss_delta_mb": peak - rss_before, "prepare_s": prepare_s, "max_abs_diff": float(diff.max()),
            "mean_abs_diff": float(diff.mean()),
            "generator": config.to_dict()}


def cpu_bf16_note() -> str:
    """Which native bf16 instructions /proc/cpuinfo lists (none means autocast emulates bf16)."""
    try:
        with open("/proc/cpuinfo") as f:
            flags = next((line for line in f if line.startswith("flags")), "").split()
    except OSError:
        return "flags unknown"
    found = [f for f in ("avx512_bf16", "amx_bf16") if f in flags]
    return ", ".join(found) if found else "no avx512_bf16 / amx_bf16"


def run(quick: bool = False, **_: object) -> dict[str, Any]:
    from bench.harness import row, run_child

    sizes = (128, 256)
    threads_list = (1,) if quick else (1, 2)
    from clone.runtime.onnx import onnx_available

    rows, notes = [], []
    options = [o for o in OPTIONS if not (quick and o == "compile")]
    if not onnx_available():
        options = [o for o in options if o not in ONNX_OPTIONS]
        notes.append("onnxruntime and int8 not measured: the optional extra `fast` is not installed")
    slow_bf16: dict[int, float] = {}  # threads -> bf16 speed-up at 128²
    for size in sizes:
        for threads in threads_list:
            args = {"size": size, "threads": threads, "repeats": 3 if quick else 5,
                    "min_time_s": 0.2 if quick else 0.5}
            base = run_child("bench.generator", {**args, "option": BASELINE})
            case = f"{size}x{size}, {threads} thread{'s' if threads > 1 else ''}"
            for option in options:
                slow = slow_bf16.get(threads)
                if option == "bf16_autocast" and size > 128 and slow is not None and slow < 0.25:
                    notes.append(f"{case}: bf16 autocast skipped: at 128² it ran at {slow:.2f}x fp32 eager "
                                 f"(this CPU has no native bf16: {cpu_bf16_note()})")
                    continue
                if option == "compile" and (threads > 1 or size > 128):
                    notes.append(f"{case}: torch.compile skipped: compiling takes ~45 s of a shared core per "
                                 "configuration here; 128², 1 thread is measured")
                    continue
                try:
                    r = base if option == BASELINE else run_child("bench.generator", {**args, "option": option},
                                                                 timeout_s=300)
                except Exception as exc:  # noqa: BLE001 - a failing option is a result, not a crash
                    notes.append(f"{case}: {option} failed or timed out: {str(exc).splitlines()[0][:200]}")
                    continue
                if option == "bf16_autocast" and size == 128:
                    slow_bf16[threads] = r["fps"] / base["fps"]
                rows.append(row(case, option, r["fps"], "frames/s", base["fps"], "eager fp32, autograd on",
                                peak_rss_mb=round(r["peak_rss_mb"], 1), rss_delta_mb=round(r["rss_delta_mb"], 1),
                                max_abs_diff=r["max_abs_diff"], mean_abs_diff=float(f"{r['mean_abs_diff']:.3g}"),
                                prepare_s=round(r["prepare_s"], 2)))
    if quick:
        notes.append("--quick: 1 thread only, compile skipped")
    notes.append("peak RSS per configuration from a fresh subprocess (VmHWM); rss_delta = peak - RSS after "
                 "importing torch and building model + input")
    notes.append("clone/drive/run.py runs the generator on ONNX Runtime in int8 when the `fast` extra is installed (the "
                 "int8 row; `--runtime onnx`: the onnxruntime row), else under torch.inference_mode (the "
                 "inference_mode row); an fp32 option is worth switching to at > 1.3x that row with max_abs_diff < "
                 "1e-2; int8's differences here come from an untrained network calibrated on random inputs: its "
                 "quality cost on a trained model is measured as SSIM against ground truth (README)")
    return {"rows": rows, "notes": notes}


if __name__ == "__main__":
    print(json.dumps(child(json.loads(sys.argv[1]))))
    with contextlib.suppress(Exception):
        sys.stdout.flush()
