"""Fixtures shared by the retargeting tests."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="module")
def one_thread():
    """One torch and one BLAS thread for a module: tiny products run faster so, and much faster on a machine
    whose other core is busy; the previous counts come back afterwards."""
    import torch

    from retarget.network.blas import blas_threads, set_blas_threads

    threads, blas = torch.get_num_threads(), blas_threads()
    torch.set_num_threads(1)
    set_blas_threads(1)
    yield
    torch.set_num_threads(threads)
    if blas is not None:
        set_blas_threads(blas)
