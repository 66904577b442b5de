"""The planned layout conversion (pose_io.layouts.convert_arrays) gives the loop's arrays bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from pose_io.layouts import LAYOUTS, JointLayout, conversion_plan, convert_arrays, convert_joints


def _loop_convert(joints, confidence, source: JointLayout, target: JointLayout):
    """convert_arrays as it was: one mean and one min per target joint."""
    if source.name == target.name:
        return joints.astype(np.float32, copy=True), confidence.astype(np.float32, copy=True)
    t = joints.shape[0]
    out = np.full((t, len(target), 2), np.nan, dtype=np.float32)
    conf = np.zeros((t, len(target)), dtype=np.float32)
    for j, src in enumerate(conversion_plan(source, target)):
        if not src:
            continue
        idx = list(src)
        out[:, j] = joints[:, idx].mean(axis=1)
        conf[:, j] = confidence[:, idx].min(axis=1)
    missing = np.isnan(out).any(axis=-1)
    out[missing] = np.nan
    conf[missing] = 0.0
    return out, conf


@pytest.mark.parametrize("source", sorted(LAYOUTS))
@pytest.mark.parametrize("target", sorted(LAYOUTS))
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_convert_arrays_is_the_loop_to_the_bit(source, target, dtype):
    rng = np.random.default_rng(len(source) * 7 + len(target))
    src, tgt = LAYOUTS[source], LAYOUTS[target]
    joints = rng.normal(300, 100, (40, len(src), 2)).astype(dtype)
    conf = rng.uniform(0, 1, (40, len(src))).astype(dtype)
    joints[rng.random((40, len(src))) < 0.2] = np.nan
    joints[rng.random((40, len(src), 2)) < 0.05] = -0.0  # signed zeros: a mean of one value makes them +0.0
    joints[3, :, 1] = np.nan  # y missing only
    conf[rng.random((40, len(src))) < 0.1] = -0.0
    got, expected = convert_arrays(joints, conf, src, tgt), _loop_convert(joints, conf, src, tgt)
    for g, e in zip(got, expected):
        assert g.dtype == e.dtype == np.float32 and g.shape == e.shape
        assert g.tobytes() == e.tobytes()  # bit for bit: NaN payloads and the sign of zero included
    assert convert_joints(joints, src, tgt).tobytes() == expected[0].tobytes()
