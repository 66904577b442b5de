"""retarget.runtime: threads for the cores actually free, and the `--device` option."""

from __future__ import annotations

import os

import pytest
import torch

from retarget.runtime import configure_threads, free_cores, resolve_device


@pytest.fixture
def machine(monkeypatch):
    """Pretend to run on ``cores`` cores with a 1-minute load of ``load``."""

    def set_machine(cores: int, load: float) -> None:
        monkeypatch.setattr(os, "sched_getaffinity", lambda pid: set(range(cores)), raising=False)
        monkeypatch.setattr(os, "getloadavg", lambda: (load, 0.0, 0.0))

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


def test_free_cores_without_a_load_average(machine, monkeypatch):
    machine(3, 0.0)

    def no_load() -> tuple[float, float, float]:
        raise OSError("not available")

    monkeypatch.setattr(os, "getloadavg", no_load)
    assert free_cores() == 3


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
