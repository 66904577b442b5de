"""The turn cases of `clone retarget eval`: windows turned in 3D, and windows that turn as captured."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from retarget.baselines.methods import global_scale_retarget
from retarget.evaluate import EvalConfig, evaluate
from retarget.evaluate.references3d import REFERENCE_FUNCTIONS
from retarget.evaluate.turns import TURN_DEGREES, CapturedTurns, TurnedMotions
from retarget.world import MotionWorld
from retarget.world.turns import facing_change


def test_turned_windows_turn_alike_on_every_character_and_captured_turns_are_found(cache: Path, tiny_mocap: Path):
    split = MotionWorld.build(tiny_mocap, cache).split("val")
    turned = TurnedMotions(split, seed=0)
    assert turned.num_motions == split.num_motions and turned.window_labels == split.window_labels
    for m in range(split.num_motions):
        a, b = turned.window3d(m, 0, 64), turned.window3d(m, 1, 64)
        assert facing_change(a) > TURN_DEGREES and facing_change(a) == pytest.approx(facing_change(b), abs=3.0)
        np.testing.assert_array_equal(a, turned.window3d(m, 0, 64))  # one turn per window, whoever asks
        assert not np.allclose(a, split.window3d(m, 0, 64))
    assert not np.allclose(turned.window3d(0, 0, 64), TurnedMotions(split, seed=1).window3d(0, 0, 64))
    # The walks of the tiny world do not turn as captured; their turned versions all do.
    assert CapturedTurns(split, 64).num_motions == 0
    captured = CapturedTurns(turned, 64)
    assert captured.num_motions == split.num_motions
    np.testing.assert_array_equal(captured.window3d(1, 0, 64), turned.window3d(1, 0, 64))


def test_the_truth_of_a_turned_case_turns_with_the_driver(cache: Path, tiny_mocap: Path):
    """The 3D rotation copy (A's bone directions on B) reproduces the turned truth's pose exactly; a 2D method
    is scored on the same cases, which differ from the captured ones."""
    split = MotionWorld.build(tiny_mocap, cache).split("val")
    config = EvalConfig(pairs=6)
    methods = {"global scaling": global_scale_retarget}
    plain = evaluate(split, methods, config)
    turned = evaluate(split, methods, config, TurnedMotions(split, config.seed))
    assert set(turned) == {"global scaling", *REFERENCE_FUNCTIONS}
    assert turned["3D rotation copy"]["pose"]["mse_x1e3"] == pytest.approx(0.0, abs=1e-6)
    assert plain["global scaling"]["pose"]["mse_x1e3"] != turned["global scaling"]["pose"]["mse_x1e3"]
