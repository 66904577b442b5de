"""retarget.runtime: threads for the cores actually free (busy now, else the load average), and `--device`."""

from __future__ import annotations

import os

import pytest
import torch

from retarget import runtime
from retarget.runtime import busy_cores, configure_threads, cpu_times, free_cores, resolve_device


@pytest.fixture
def machine(monkeypatch):
    """Pretend to run on ``cores`` cores of which other processes keep ``load`` busy now (the 1-minute load
    average says 0, as just after a quiet minute; see the tests of the fallback for the other way round)."""

    def set_machine(cores: int, load: float) -> None:
        monkeypatch.setattr(os, "sched_getaffinity", lambda pid: set(range(cores)), raising=False)
        monkeypatch.setattr(runtime, "busy_cores", lambda allowed: load if allowed == set(range(cores)) else None)
        monkeypatch.setattr(os, "getloadavg", lambda: (0.0, 0.0, 0.0))

    return set_machine


@pytest.fixture
def restore_threads():
    threads = torch.get_num_threads()
    yield
    torch.set_num_threads(threads)


@pytest.mark.parametrize(("cores", "load", "free"), [(8, 0.0, 8), (8, 2.4, 6), (8, 2.6, 5), (2, 1.0, 1),
                                                      (2, 7.0, 1), (4, -0.2, 4)])
def test_free_cores(machine, cores, load, free):
    machine(cores, load)
    assert free_cores() == free


def test_without_proc_stat_the_load_average_decides_and_without_either_every_core_is_free(machine, monkeypatch):
    machine(3, 0.0)
    monkeypatch.setattr(runtime, "busy_cores", lambda allowed: None)  # not Linux, or /proc unreadable
    monkeypatch.setattr(os, "getloadavg", lambda: (1.7, 0.0, 0.0))
    assert free_cores() == 1

    def no_load() -> tuple[float, float, float]:
        raise OSError("not available")

    monkeypatch.setattr(os, "getloadavg", no_load)
    assert free_cores() == 3


def test_a_lagging_load_average_does_not_hide_cores_that_are_idle_now(machine, monkeypatch):
    machine(2, 0.05)  # the install that raised the load has ended
    monkeypatch.setattr(os, "getloadavg", lambda: (1.4, 0.6, 0.2))
    assert free_cores() == 2
    assert free_cores(now=False) == 1  # processes started together read the load average only


STAT = """cpu  400 10 100 900 50 5 5 30 0 0
cpu0 100 0 50 800 20 0 0 30 7 0
cpu1 300 10 50 100 30 5 5 0 0 0
intr 12345 0 0
cpu9x 1 2 3
"""


def test_cpu_times_adds_the_busy_and_total_ticks_of_the_cores_asked_for(tmp_path):
    stat = tmp_path / "stat"
    stat.write_text(STAT)
    assert cpu_times({0}, str(stat)) == (100 + 50 + 30, 100 + 50 + 800 + 20 + 30)  # steal is busy, iowait free
    assert cpu_times({1}, str(stat)) == (300 + 10 + 50 + 5 + 5, 300 + 10 + 50 + 100 + 30 + 5 + 5)
    assert cpu_times({0, 1}, str(stat)) == (180 + 370, 1000 + 500)
    assert cpu_times({5}, str(stat)) is None  # none of the cores listed
    assert cpu_times({0}, str(tmp_path / "missing")) is None
    stat.write_text("cpu0 1 x 3\n")
    assert cpu_times({0}, str(stat)) is None


def test_busy_cores_is_the_busy_share_between_two_readings_times_the_cores(monkeypatch):
    readings = iter([(1000, 4000), (1030, 4040)])  # 30 of 40 ticks busy over two cores
    monkeypatch.setattr(runtime, "cpu_times", lambda cores, path: next(readings))
    monkeypatch.setattr("time.sleep", lambda seconds: None)
    assert busy_cores({0, 1}) == pytest.approx(1.5)
    stalled = iter([(1000, 4000), (1000, 4000)])  # no tick in between: nothing to say
    monkeypatch.setattr(runtime, "cpu_times", lambda cores, path: next(stalled))
    assert busy_cores({0, 1}) is None


@pytest.mark.skipif(not os.path.exists("/proc/stat"), reason="Linux only")
def test_busy_cores_reads_this_machine():
    allowed = set(os.sched_getaffinity(0))
    busy = busy_cores(allowed)
    assert busy is not None and 0.0 <= busy <= len(allowed)


def test_configure_threads(machine, restore_threads):
    machine(4, 1.0)
    assert configure_threads(2) == 2 and torch.get_num_threads() == 2
    assert configure_threads() == 3 and torch.get_num_threads() == 3  # the free cores
    assert configure_threads(0) == 3


def test_resolve_device(monkeypatch):
    assert resolve_device("cpu") == torch.device("cpu")
    assert resolve_device(" CPU ") == torch.device("cpu")
    monkeypatch.setattr(torch.cuda, "is_available", lambda: False)
    assert resolve_device() == torch.device("cpu")
    assert resolve_device("auto") == torch.device("cpu")
    with pytest.raises(ValueError, match="device 'cuda:1' asked for, but no CUDA GPU is available"):
        resolve_device("cuda:1")
    with pytest.raises(ValueError, match="unknown device 'tpu'; valid: auto, cpu, cuda, cuda:N"):
        resolve_device("tpu")
    monkeypatch.setattr(torch.cuda, "is_available", lambda: True)
    assert resolve_device("auto") == torch.device("cuda")
    assert resolve_device("cuda:1") == torch.device("cuda", 1)


def test_thread_growth_raises_threads_when_cores_come_free_and_never_lowers(monkeypatch):
    import torch

    from retarget import runtime

    before = torch.get_num_threads()
    try:
        torch.set_num_threads(1)
        free = iter([2, 1])
        monkeypatch.setattr(runtime, "free_cores", lambda: next(free))
        grow = runtime.ThreadGrowth(every_s=0.0)
        assert grow() == 2 and torch.get_num_threads() == 2  # a core came free
        assert grow() is None and torch.get_num_threads() == 2  # busy again: kept
        waiting = runtime.ThreadGrowth(every_s=3600.0)
        assert waiting() is None  # not due: nothing sampled (the iterator is spent)
    finally:
        torch.set_num_threads(before)
