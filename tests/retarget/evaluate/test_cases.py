"""Case sampling and extra mocap clips."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pose_io.errors import InputError
from retarget.evaluate import ClipMotions, EvalConfig, sample_cases
from retarget.world import MotionWorld, load_motion
from tests.retarget.evaluate.helpers import TINY


def test_cases_are_seeded_and_references_share_no_frame(cache: Path, tiny_mocap: Path) -> None:
    split = MotionWorld.build(tiny_mocap, cache).split("test")  # one clip of 138 frames: windows overlap
    config = EvalConfig(pairs=40)
    cases = sample_cases(split, split, config, np.random.default_rng(3))
    assert cases == sample_cases(split, split, config, np.random.default_rng(3))
    for case in cases:
        assert case.source_character != case.character
        drv, ref = split.window_labels[case.motion], split.window_labels[case.reference]
        assert drv.start + 64 <= ref.start or ref.start + 64 <= drv.start
        assert abs(case.pitch) <= config.max_pitch
    with pytest.raises(InputError, match="shares none"):
        sample_cases(split, split, EvalConfig(pairs=1, length=128), np.random.default_rng(0))


def test_max_yaw_keeps_cameras_near_the_front(cache: Path, tiny_mocap: Path) -> None:
    split = MotionWorld.build(tiny_mocap, cache).split("test")
    everything = sample_cases(split, split, EvalConfig(pairs=80, max_yaw=90), np.random.default_rng(3))
    # 90 is the paper's protocol: every bin, and the very cases drawn before the option existed (recorded from
    # that code: motion, character and view of A, character and view of B, reference).
    assert [(c.motion, c.source_character, c.source_view, c.character, c.view, c.reference)
            for c in everything[:4]] == [(3, 2, 2, 1, 10, 0), (0, 8, 3, 5, 2, 2), (2, 6, 5, 10, 8, 0),
                                         (2, 3, 8, 9, 8, 0)]  # fmt: skip
    yaws = np.asarray(split.views)
    assert max(abs(yaws[c.view]) for c in everything) == 90
    near = sample_cases(split, split, EvalConfig(pairs=80, max_yaw=45), np.random.default_rng(3))
    seen = {yaws[v] for c in near for v in (c.source_view, c.view)}
    assert seen == {-45.0, -30.0, -15.0, 0.0, 15.0, 30.0, 45.0}
    front = sample_cases(split, split, EvalConfig(pairs=5, max_yaw=0), np.random.default_rng(3))
    assert all(yaws[c.source_view] == yaws[c.view] == 0 for c in front)


def test_extra_clips_replay_like_the_world(cache: Path, tiny_mocap: Path) -> None:
    split = MotionWorld.build(tiny_mocap, cache).split("test")
    motion = load_motion(tiny_mocap / Path(TINY[1]).name)  # the test split's own clip
    clips = ClipMotions([motion], split.characters, 64, 32)
    assert [lab.start for lab in clips.window_labels] == [lab.start for lab in split.window_labels]
    for m in range(clips.num_motions):
        assert np.allclose(clips.window3d(m, 2), split.window3d(m, 2), atol=1e-5)
    with pytest.raises(InputError, match="shorter"):
        ClipMotions([motion], split.characters, 512, 32)


def test_detector_noise_reaches_the_methods_only(cache: Path, tiny_mocap: Path) -> None:
    from retarget.evaluate import evaluate

    split = MotionWorld.build(tiny_mocap, cache).split("test")
    seen: list[np.ndarray] = []

    def copy(motion, reference):  # the driver unchanged: its error is the inputs' noise plus retargeting's
        seen.append(np.asarray(motion.joints, np.float64))
        return motion

    clean = evaluate(split, {"copy": copy}, EvalConfig(pairs=6))
    noisy = evaluate(split, {"copy": copy}, EvalConfig(pairs=6, noise=0.01))
    again = evaluate(split, {"copy": copy}, EvalConfig(pairs=6, noise=0.01))
    assert noisy == again  # seeded
    assert noisy["copy"]["pose"]["mse_x1e3"] > clean["copy"]["pose"]["mse_x1e3"]
    for name in noisy:
        if name != "copy":  # the 3D references see the truth, never the noisy inputs
            assert noisy[name] == clean[name]
    # The noise is about 1 % of the height per coordinate.
    diff = seen[6] - seen[0]  # case 0 with and without noise
    height = split.characters[0].height * split.camera(0).scale
    assert 0.3 < float(np.nanstd(diff)) / (0.01 * height) < 3.0
    with pytest.raises(ValueError, match="noise"):
        EvalConfig(noise=0.5)
