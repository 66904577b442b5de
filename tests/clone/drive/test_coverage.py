"""Pose coverage: driven frames measured against the poses the reference showed."""

from __future__ import annotations

import numpy as np

from clone.drive.coverage import pose_coverage
from pose_io.layouts import BODY15
from pose_io.track import PoseTrack

# A person facing the camera (their left on the image's right), arms down, feet under the hips; y down, 200 px tall.
STANDING = {
    "nose": (200, 100), "neck": (200, 125), "r_shoulder": (180, 125), "r_elbow": (175, 165), "r_wrist": (172, 200),
    "l_shoulder": (220, 125), "l_elbow": (225, 165), "l_wrist": (228, 200), "mid_hip": (200, 205),
    "r_hip": (188, 205), "r_knee": (187, 250), "r_ankle": (186, 295), "l_hip": (212, 205), "l_knee": (213, 250),
    "l_ankle": (214, 295),
}


def pose(**changes: tuple[float, float]) -> np.ndarray:
    joints = dict(STANDING, **changes)
    return np.array([joints[name] for name in BODY15.joints], dtype=np.float32)


def track(frames: list[np.ndarray], fps: float = 10.0) -> PoseTrack:
    joints = np.stack(frames)
    return PoseTrack(joints, np.ones(joints.shape[:2], np.float32), fps, (400, 400), "body15")


def swaying(n: int, seed: int = 0) -> list[np.ndarray]:
    """The standing pose with the arms swinging a little and some detection noise."""
    rng = np.random.default_rng(seed)
    out = []
    for t in range(n):
        swing = 8 * np.sin(t / 4)
        p = pose(r_wrist=(172 + swing, 200), l_wrist=(228 - swing, 200))
        out.append(p + rng.normal(0, 1.0, p.shape).astype(np.float32))
    return out


def test_the_reference_covers_itself_and_a_similar_drive():
    reference = track(swaying(60))
    assert pose_coverage(reference, reference).line() is None
    drive = track(swaying(40, seed=1))
    cover = pose_coverage(drive, reference)
    assert cover.share == 0 and cover.line() is None
    assert np.all(cover.distance < cover.threshold)


def test_raised_arms_are_named():
    reference = track(swaying(60))
    raised = pose(r_elbow=(175, 95), r_wrist=(172, 60), l_elbow=(225, 95), l_wrist=(228, 60))
    cover = pose_coverage(track(swaying(10) + [raised] * 10), reference)
    assert cover.share == 0.5
    assert cover.outside[10:].all() and not cover.outside[:10].any()
    assert cover.parts["arms above the head"] == 0.5
    line = cover.line()
    assert line.startswith("coverage: 50% of the frames") and "arms above the head 50%" in line


def test_a_wide_stance_and_a_turned_back_are_named():
    reference = track(swaying(60))
    wide = pose(r_knee=(160, 250), r_ankle=(130, 295), l_knee=(240, 250), l_ankle=(270, 295))
    other_side = {"r_": "l_", "l_": "r_"}
    # Seen from behind: every left joint where the right one was (the left shoulder on the image's left).
    back = pose(**{name: STANDING[other_side[name[:2]] + name[2:]] for name in STANDING if name[:2] in other_side})
    cover = pose_coverage(track([wide] * 5 + [back] * 5 + swaying(10)), reference)
    assert cover.outside[:5].all()
    assert cover.parts.get("wide stance") == 0.25
    assert "back to the camera" in cover.parts
