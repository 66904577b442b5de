"""Threads of numpy's BLAS (the matrix products of the torch-free path), set at run time without extra packages.

OpenBLAS starts as many threads as there are cores and, on a machine where another process keeps a core busy,
its threads wait for each other: small products ran 30x slower with 2 threads than with 1 on the shared 2-core
machine. The library is found among the shared objects this process has loaded (as threadpoolctl does) and its
``*openblas_set_num_threads*`` entry point is called; elsewhere (no OpenBLAS, not Linux) nothing changes.
"""

from __future__ import annotations

import ctypes
import functools
import logging
from pathlib import Path

log = logging.getLogger(__name__)

# Entry points of the OpenBLAS builds numpy ships with (scipy-openblas, 64-bit ints) and of plain builds.
_SETTERS = ("scipy_openblas_set_num_threads64_", "openblas_set_num_threads64_", "openblas_set_num_threads")
_GETTERS = ("scipy_openblas_get_num_threads64_", "openblas_get_num_threads64_", "openblas_get_num_threads")


@functools.cache
def _openblas() -> tuple[ctypes.CDLL, str, str] | None:
    """(library, setter name, getter name) of the OpenBLAS numpy loaded, or None."""
    import numpy  # noqa: F401 - loads its BLAS, which is what we look for

    try:
        maps = Path("/proc/self/maps").read_text()
    except OSError:
        return None
    paths = sorted({line.split()[-1] for line in maps.splitlines() if "openblas" in line.lower() and "/" in line})
    for path in paths:
        try:
            lib = ctypes.CDLL(path)
        except OSError:
            continue
        setter = next((s for s in _SETTERS if hasattr(lib, s)), None)
        getter = next((g for g in _GETTERS if hasattr(lib, g)), None)
        if setter and getter:
            return lib, setter, getter
    return None


def blas_threads() -> int | None:
    """Threads numpy's OpenBLAS uses now, or None when it cannot be told."""
    found = _openblas()
    if found is None:
        return None
    lib, _, getter = found
    return int(getattr(lib, getter)())


def set_blas_threads(threads: int) -> bool:
    """Make numpy's OpenBLAS use ``threads`` threads (>= 1); False when it cannot be set here."""
    found = _openblas()
    if found is None:
        log.debug("numpy's BLAS threads cannot be set here")
        return False
    lib, setter, _ = found
    getattr(lib, setter)(max(1, int(threads)))
    log.debug("numpy BLAS threads: %d", threads)
    return True
