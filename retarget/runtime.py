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


PROC_STAT = "/proc/stat"
SAMPLE_SECONDS = 0.1  # long enough for 10 ticks per core at Linux's 100 Hz, short enough for every command start


def cpu_times(cores: set[int], path: str = PROC_STAT) -> tuple[int, int] | None:
    """Busy and total clock ticks of ``cores`` since boot, from Linux's /proc/stat; None where it is unreadable.

    Busy is user, nice, system, irq, softirq and steal time (a core the hypervisor lends elsewhere is not free);
    idle and iowait are free time.
    """
    busy = total = 0
    seen = 0
    try:
        with open(path, encoding="ascii") as f:
            for line in f:
                name, *fields = line.split()
                if not name.startswith("cpu") or not name[3:].isdigit() or int(name[3:]) not in cores:
                    continue
                ticks = [int(v) for v in fields[:8]]
                user, nice, system, idle, iowait, irq, softirq, steal = ticks + [0] * (8 - len(ticks))
                busy += user + nice + system + irq + softirq + steal
                total += user + nice + system + idle + iowait + irq + softirq + steal
                seen += 1
    except (OSError, ValueError):
        return None
    return (busy, total) if seen else None


def busy_cores(cores: set[int], seconds: float = SAMPLE_SECONDS, path: str = PROC_STAT) -> float | None:
    """How many of ``cores`` other processes keep busy now: their busy share over ``seconds`` (this process
    sleeps meanwhile) times their number; None without /proc/stat."""
    import time

    before = cpu_times(cores, path)
    if before is None:
        return None
    time.sleep(seconds)
    after = cpu_times(cores, path)
    if after is None or after[1] <= before[1]:
        return None
    return len(cores) * (after[0] - before[0]) / (after[1] - before[1])


def free_cores(now: bool = True) -> int:
    """Cores this process may use that are not already busy (at least 1).

    Uses the CPU affinity mask and how busy those cores are now (a tenth of a second of /proc/stat); where that
    cannot be read, or with ``now=False``, the 1-minute load average, which lags: just after an install or a
    finished job it still counts cores that are idle again. Two threads on a core another process keeps busy are
    many times slower than one.

    Args:
        now: read how busy the cores are now. Processes started together (torchrun) pass False: each would count
            its siblings, busy importing beside it, as other work.
    """
    try:
        allowed = set(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        allowed = set(range(os.cpu_count() or 1))
    cores = len(allowed)
    load = busy_cores(allowed) if now else None
    if load is None:
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


class ThreadGrowth:
    """For a long CPU run: every ``every_s`` seconds, raise torch's threads to the cores free now, never lower.

    A run's threads are chosen from the free cores at its start, so a moment's load then (an install, a test
    finishing) would halve a ten-minute run. Call the object once per training step; it samples (a tenth of a
    second, this process idle meanwhile) only when ``every_s`` have passed. Returns the new count when it grew.
    """

    def __init__(self, every_s: float = 30.0) -> None:
        import time

        self.every_s = every_s
        self._last = time.perf_counter()

    def __call__(self) -> int | None:
        import time

        import torch

        now = time.perf_counter()
        if now - self._last < self.every_s:
            return None
        free = free_cores()
        self._last = time.perf_counter()
        current = torch.get_num_threads()
        if free <= current:
            return None
        torch.set_num_threads(free)
        log.info("torch threads: %d -> %d (cores came free)", current, free)
        return free


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
