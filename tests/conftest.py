"""Shared fixtures: small tracks built in memory; paths to ../shared when it is there."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from pose_io import PoseTrack

SHARED = Path(__file__).resolve().parents[1].parent / "shared"


@pytest.fixture(scope="session")
def shared_dir() -> Path:
    """../shared (the authors' arrays, OpenPose examples, mocap); skips when absent or ``CLONE2D_NO_SHARED`` is set.

    ``CLONE2D_NO_SHARED=1`` runs the suite as a user of the sdist would, without ../shared.
    """
    if os.environ.get("CLONE2D_NO_SHARED", "") not in ("", "0"):
        pytest.skip("CLONE2D_NO_SHARED is set")
    if not SHARED.is_dir():
        pytest.skip("../shared is not present")
    return SHARED


@pytest.fixture(autouse=True)
def _no_int8_prepare(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> None:
    """`clone train-ref` quantises its new generator for `clone drive` (2-3 s even at 32²); the suite trains
    dozens of tiny models in-process, so only tests marked ``prepare_drive`` run that step."""
    if request.node.get_closest_marker("prepare_drive"):
        return
    from clone.cli import cloning

    monkeypatch.setattr(cloning, "_prepare_drive", lambda model_path: None)


@pytest.fixture
def walking_track() -> PoseTrack:
    """A 40-frame body25 track of a figure whose arms and legs swing, at 30 fps in a 640x480 frame."""
    rng = np.random.default_rng(0)
    t = np.arange(40)[:, None]
    base = np.array(
        [[320, 100], [320, 140], [290, 140], [280, 190], [275, 240], [350, 140], [360, 190], [365, 240],
         [320, 250], [300, 250], [300, 320], [300, 390], [340, 250], [340, 320], [340, 390], [312, 92],
         [328, 92], [305, 98], [335, 98], [345, 405], [352, 403], [335, 398], [295, 405], [288, 403],
         [305, 398]], dtype=np.float32)
    joints = np.repeat(base[None], 40, axis=0)
    joints[:, [4, 7, 11, 14], 0] += 15 * np.sin(t / 5.0)
    joints += rng.normal(0, 0.5, joints.shape).astype(np.float32)
    conf = np.full(joints.shape[:2], 0.9, dtype=np.float32)
    return PoseTrack(joints, conf, 30.0, (640, 480), "body25")


def pytest_terminal_summary(terminalreporter, exitstatus, config) -> None:
    """Say how many tests skipped because ../shared (mocap, the authors' arrays, OpenPose and real examples) is absent."""
    skipped = terminalreporter.stats.get("skipped", [])
    reasons = [str(r.longrepr[2]) if isinstance(r.longrepr, tuple) else str(r.longrepr) for r in skipped]
    shared = [r for r in reasons if "../shared" in r or "CLONE2D_NO_SHARED" in r]
    if shared:
        terminalreporter.write_line(
            f"{len(shared)} tests skipped: they read real data from ../shared ({shared[0].split(': ')[-1]}); "
            "the rest of the suite ran without it"
        )
