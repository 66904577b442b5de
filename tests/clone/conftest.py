"""Fixtures for every clone test: quantised generators are cached in a temporary folder, not the user's home."""

from __future__ import annotations

from pathlib import Path

import pytest


@pytest.fixture(scope="session")
def _int8_cache(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("int8_cache")


@pytest.fixture(autouse=True)
def _int8_cache_in_tmp(_int8_cache: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """`clone drive` and reports pick the int8 runtime when onnxruntime is installed; keep its cache here."""
    from clone.runtime import int8 as int8_generator

    monkeypatch.setattr(int8_generator, "generator_cache_dir", lambda: _int8_cache)
