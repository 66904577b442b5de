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
from dataclasses import asdict, dataclass, field
from typing import Callable


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
    """Peak resident memory of this process so far, in MiB (Linux reports KiB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


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
