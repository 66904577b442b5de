"""Timing and memory helpers shared by the benchmarks.

Every figure is the median of repeated runs after warm-up; every stage is compared with a baseline
measured in the same process, so the ratios hold on any machine even when absolute times do not.
"""

from __future__ import annotations

import gc
import platform
import resource
import statistics
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field


@dataclass
class Timing:
    """Median seconds per call over ``repeats`` runs after ``warmup`` runs."""

    median_s: float
    repeats: int
    samples_s: list[float] = field(default_factory=list)

    def rate(self, items: float) -> float:
        """Items per second at the median time."""
        return items / self.median_s if self.median_s > 0 else float("inf")


def time_call(fn: Callable[[], object], repeats: int = 5, warmup: int = 1, min_time_s: float = 0.0) -> Timing:
    """Time ``fn`` ``repeats`` times after ``warmup`` calls; each sample lasts at least ``min_time_s``.

    A sample shorter than ``min_time_s`` loops ``fn`` and divides, so fast functions are not timer noise.
    """
    for _ in range(warmup):
        fn()
    samples: list[float] = []
    for _ in range(repeats):
        gc.collect()
        n = 0
        start = time.perf_counter()
        while True:
            fn()
            n += 1
            elapsed = time.perf_counter() - start
            if elapsed >= min_time_s:
                break
        samples.append(elapsed / n)
    return Timing(statistics.median(samples), repeats, samples)


def peak_rss_mb() -> float:
    """Peak resident memory of this process so far, in MiB.

    Reads ``VmHWM`` from /proc/self/status: ``ru_maxrss`` survives ``exec``, so a subprocess started by a
    big parent would report at least the parent's RSS at the fork. Falls back to ``ru_maxrss`` elsewhere.
    """
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024.0
    except (OSError, ValueError, IndexError):
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # Linux reports KiB


def machine_info() -> dict[str, object]:
    import os

    import torch

    return {
        "machine": platform.machine(),
        "processor": platform.processor() or platform.machine(),
        "cpus_available": len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count(),
        "python": platform.python_version(),
        "torch": torch.__version__,
        "torch_threads": torch.get_num_threads(),
        "cuda": torch.cuda.get_device_name(0) if torch.cuda.is_available() else None,
        "date": time.strftime("%Y-%m-%d %H:%M:%S %Z"),
    }


def as_dict(obj: object) -> object:
    return asdict(obj) if hasattr(obj, "__dataclass_fields__") else obj


def load_average() -> list[float]:
    """1-, 5- and 15-minute load averages (the machine is shared: every figure carries them)."""
    import os

    try:
        return [round(v, 2) for v in os.getloadavg()]
    except OSError:  # not on Unix
        return []


def row(
    case: str,
    variant: str,
    value: float,
    unit: str,
    baseline: float | None = None,
    baseline_variant: str | None = None,
    higher_is_better: bool = True,
    **extra: object,
) -> dict[str, object]:
    """One result: ``value`` of ``variant`` and, when given, the same-run baseline and the speed-up over it.

    ``speedup`` is value / baseline for rates (frames/s) and baseline / value for times and memory, so
    above 1 always means better than the baseline.
    """
    speedup = None
    if baseline is not None and value > 0 and baseline > 0:
        speedup = value / baseline if higher_is_better else baseline / value
    return {
        "case": case,
        "variant": variant,
        "value": float(value),
        "unit": unit,
        "baseline_variant": baseline_variant,
        "baseline": None if baseline is None else float(baseline),
        "speedup": None if speedup is None else round(speedup, 3),
        "load_average": load_average(),
        "extra": extra,
    }


def run_child(module: str, args: dict[str, object], timeout_s: float = 600.0) -> dict[str, object]:
    """Run ``python -m <module> '<json args>'`` in a fresh process and return the JSON of its last stdout line.

    A fresh process per configuration makes its peak RSS (``VmHWM``, see :func:`peak_rss_mb`) that configuration's alone.

    Raises:
        RuntimeError: the child failed or printed no JSON (its stderr tail is in the message).
    """
    import json
    import subprocess
    import sys

    proc = subprocess.run(
        [sys.executable, "-m", module, json.dumps(args)], capture_output=True, text=True, timeout=timeout_s,
        check=False,
    )
    lines = [line for line in proc.stdout.splitlines() if line.startswith("{")]
    if proc.returncode != 0 or not lines:
        raise RuntimeError(f"{module} {args} failed (exit {proc.returncode}): {proc.stderr[-2000:]}")
    return json.loads(lines[-1])


def rss_mb() -> float:
    """Current resident memory of this process in MiB (Linux /proc; falls back to the peak)."""
    try:
        with open("/proc/self/statm") as f:
            pages = int(f.read().split()[1])
        import os

        return pages * os.sysconf("SC_PAGE_SIZE") / 2**20
    except (OSError, ValueError, IndexError):
        return peak_rss_mb()
