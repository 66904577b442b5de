"""What an evaluation measures: the paper's defaults and the checks on them."""

from __future__ import annotations

import pytest

from retarget.evaluate import EvalConfig
from retarget.evaluate.config import DEFAULT_CONFIG


def test_defaults_and_invalid_settings() -> None:
    assert DEFAULT_CONFIG == EvalConfig()
    assert (DEFAULT_CONFIG.pairs, DEFAULT_CONFIG.length, DEFAULT_CONFIG.code_samples) == (500, 64, 6)
    for bad in ({"pairs": 0}, {"length": 4}, {"reference_length": 4}, {"code_samples": 1}, {"max_pitch": -1.0},
                {"max_yaw": -1.0}, {"max_yaw": 91.0}):
        with pytest.raises(ValueError):
            EvalConfig(**bad)
