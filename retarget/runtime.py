"""Where torch runs: thread count for the cores actually free, and the `--device` option.

torch is imported inside the functions that need it: :func:`free_cores` also serves the torch-free path.
"""

from __future__ import annotations

import logging
import os
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import torch

log = logging.getLogger(__name__)


def free_cores() -> int:
    """Cores this process may use that are not already busy (at least 1).

    Uses the CPU affinity mask and the 1-minute load average: two threads on a core another process
    keeps busy are many times slower than one.
    """
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        cores = os.cpu_count() or 1
    try:
        load = os.getloadavg()[0]
    except OSError:
        load = 0.0
    return max(1, min(cores, int(cores - load + 0.5)))


def configure_threads(threads: int | None = None) -> int:
    """Set torch's intra-op threads to ``threads`` or to the free cores; returns the number set."""
    import torch

    n = threads if threads and threads > 0 else free_cores()
    torch.set_num_threads(n)
    log.debug("torch threads: %d", n)
    return n


def resolve_device(spec: str = "auto") -> torch.device:
    """``auto`` -> CUDA when available else CPU; ``cpu``; ``cuda`` or ``cuda:N``.

    Raises:
        ValueError: unknown spec, or CUDA asked for but not available.
    """
    import torch

    spec = spec.strip().lower()
    if spec == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    if spec == "cpu":
        return torch.device("cpu")
    if spec == "cuda" or spec.startswith("cuda:"):
        if not torch.cuda.is_available():
            raise ValueError(f"device {spec!r} asked for, but no CUDA GPU is available")
        return torch.device(spec)
    raise ValueError(f"unknown device {spec!r}; valid: auto, cpu, cuda, cuda:N")
