"""3D references against the world's own answer."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from retarget.evaluate import REFERENCES_3D, case_scores, global_scale_3d, naive_copy_3d, rotation_copy_3d
from retarget.evaluate.references3d import REFERENCE_FUNCTIONS
from retarget.world import MotionWorld


def test_3d_references_against_the_world_truth(cache: Path, tiny_mocap: Path) -> None:
    split = MotionWorld.build(tiny_mocap, cache).split("test")
    a, b = 0, split.num_characters - 1
    skel_a, skel_b = split.characters[a], split.characters[b]
    pos_a = split.window3d(0, a)
    truth = split.window(0, b, 4)
    height = skel_b.height * split.camera(4).scale
    seen = {f.__name__: split.project(f(pos_a, skel_a, skel_b)[None], [4])[0]
            for f in (naive_copy_3d, global_scale_3d, rotation_copy_3d)}  # fmt: skip
    # Rotations copied onto B's bones are the truth's pose exactly; only the root path differs.
    assert case_scores(seen["rotation_copy_3d"], truth, height)["pose"]["rmse_pct"] < 1e-3
    assert case_scores(seen["naive_copy_3d"], truth, height)["pose"]["rmse_pct"] > 1.0
    # Onto A's own skeleton every reference is the identity.
    for f in (naive_copy_3d, global_scale_3d, rotation_copy_3d):
        assert np.allclose(f(pos_a, skel_a, skel_a), pos_a, atol=1e-5)
    assert set(REFERENCES_3D) == {"3D naive copy", "3D global scale", "3D rotation copy"}
    assert list(REFERENCE_FUNCTIONS) == list(REFERENCES_3D)  # every described row has its function, in order
