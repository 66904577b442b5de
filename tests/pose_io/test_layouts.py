"""pose_io.layouts: joint layouts as data (names, limbs, mirror pairs, colours) and conversions between them."""

from __future__ import annotations

import numpy as np
import pytest

from pose_io import BODY15, BODY25, COCO17, COCO18, LAYOUTS, MEDIAPIPE33, InputError, JointLayout, get_layout
from pose_io.layouts import DERIVED, conversion_plan, convert_arrays, require_convertible


def test_registry_names_its_layouts():
    assert set(LAYOUTS) == {"body25", "body15", "coco18", "coco17", "mediapipe33", "body31"}
    for name, layout in LAYOUTS.items():
        assert layout.name == name and get_layout(name) is layout
    assert [len(LAYOUTS[n]) for n in ("body25", "body15", "coco18", "coco17", "mediapipe33", "body31")] == [
        25, 15, 18, 17, 33, 31]


def test_unknown_layout_lists_valid_ones():
    with pytest.raises(ValueError, match="unknown joint layout 'smpl'; valid: body15, body25, body31, coco17, coco18"):
        get_layout("smpl")


def test_body15_is_the_first_15_body25_joints():
    assert BODY15.joints == BODY25.joints[:15]
    assert BODY15.colors == BODY25.colors[:15]
    assert BODY15.index("mid_hip") == 8 and BODY25.index("r_heel") == 24  # OpenPose's BODY_25 order


@pytest.mark.parametrize("layout", list(LAYOUTS.values()), ids=list(LAYOUTS))
def test_every_layout_is_consistent(layout):
    assert len(layout.colors) == len(layout)
    assert all(len(c) == 3 and all(0 <= v <= 255 for v in c) for c in layout.colors)
    limbs = layout.limb_indices
    assert limbs.shape == (len(layout.limbs), 2) and limbs.dtype == np.int64
    assert [(layout.joints[a], layout.joints[b]) for a, b in limbs] == list(layout.limbs)
    assert layout.indices(list(layout.joints)) == list(range(len(layout)))
    # Mirroring is an involution that swaps l_/r_ joints and _left/_right ones and keeps the others.
    perm = layout.mirror
    np.testing.assert_array_equal(perm[perm], np.arange(len(layout)))
    for i, name in enumerate(layout.joints):
        other = layout.joints[perm[i]]
        if name.startswith(("l_", "r_")):
            assert other[2:] == name[2:] and other[0] != name[0]
        elif name.endswith(("_left", "_right")):
            assert other.rsplit("_", 1)[0] == name.rsplit("_", 1)[0] and other != name
        else:
            assert other == name


def test_index_by_name_and_a_clear_error():
    assert BODY25.index("l_wrist") == 7 and BODY25.has("l_wrist") and not BODY25.has("tail")
    assert BODY25.joints[BODY25.mirror[BODY25.index("l_wrist")]] == "r_wrist"
    with pytest.raises(KeyError, match="layout coco17 has no joint 'neck'; joints: nose, l_eye"):
        COCO17.index("neck")


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"joints": ("a", "a"), "limbs": (), "colors": ((0, 0, 0),) * 2}, "duplicate joint names"),
        ({"joints": ("a", "b"), "limbs": (), "colors": ((0, 0, 0),)}, "1 colours for 2 joints"),
        ({"joints": ("a", "b"), "limbs": (("a", "c"),), "colors": ((0, 0, 0),) * 2}, "limb \\(a, c\\) names an unknown"),
    ],
)
def test_a_bad_layout_is_refused(kwargs, message):
    with pytest.raises(ValueError, match=message):
        JointLayout(name="bad", **kwargs)


def test_a_layout_of_its_own():
    layout = JointLayout("stick", ("head", "l_hand", "r_hand"), (("head", "l_hand"), ("head", "r_hand")),
                         ((1, 2, 3), (4, 5, 6), (7, 8, 9)))
    np.testing.assert_array_equal(layout.mirror, [0, 2, 1])
    np.testing.assert_array_equal(layout.limb_indices, [[0, 1], [0, 2]])


def test_conversion_plan_copies_by_name_and_derives_the_rest():
    plan = dict(zip(BODY25.joints, conversion_plan(MEDIAPIPE33, BODY25)))
    assert plan["nose"] == (MEDIAPIPE33.index("nose"),)
    assert plan["neck"] == tuple(MEDIAPIPE33.indices(DERIVED["neck"]))
    assert plan["mid_hip"] == (MEDIAPIPE33.index("l_hip"), MEDIAPIPE33.index("r_hip"))
    assert plan["l_big_toe"] == (MEDIAPIPE33.index("l_foot_index"),)
    assert plan["l_small_toe"] == ()  # nothing to make it from
    assert conversion_plan(BODY15, BODY15) == [(j,) for j in range(15)]


def test_convert_arrays_known_values():
    rng = np.random.default_rng(0)
    joints = rng.uniform(0, 100, (3, 17, 2)).astype(np.float32)
    conf = rng.uniform(0.2, 1.0, (3, 17)).astype(np.float32)
    out, out_conf = convert_arrays(joints, conf, COCO17, BODY15)
    assert out.shape == (3, 15, 2) and out_conf.shape == (3, 15) and out.dtype == np.float32
    ls, rs = COCO17.index("l_shoulder"), COCO17.index("r_shoulder")
    np.testing.assert_allclose(out[:, BODY15.index("neck")], (joints[:, ls] + joints[:, rs]) / 2, rtol=1e-6)
    # A derived joint is as sure as its least sure part.
    np.testing.assert_array_equal(out_conf[:, BODY15.index("neck")], np.minimum(conf[:, ls], conf[:, rs]))
    np.testing.assert_array_equal(out[:, BODY15.index("l_knee")], joints[:, COCO17.index("l_knee")])


def test_convert_arrays_marks_what_cannot_be_made_missing():
    joints = np.ones((2, 15, 2), np.float32)
    joints[1, BODY15.index("l_hip")] = np.nan
    conf = np.ones((2, 15), np.float32)
    conf[1, BODY15.index("l_hip")] = 0.0
    out, out_conf = convert_arrays(joints, conf, BODY15, BODY25)
    assert np.isnan(out[:, BODY25.index("l_heel")]).all() and (out_conf[:, BODY25.index("l_heel")] == 0).all()
    assert np.isnan(out[1, BODY25.index("l_hip")]).all() and out_conf[1, BODY25.index("l_hip")] == 0
    back, _ = convert_arrays(out, out_conf, BODY25, BODY15)
    np.testing.assert_array_equal(back, joints)  # body15 -> body25 -> body15 round trip


def test_same_layout_is_a_copy():
    joints = np.zeros((1, 18, 2), np.float64)
    out, _ = convert_arrays(joints, np.ones((1, 18)), COCO18, COCO18)
    assert out.dtype == np.float32 and not np.shares_memory(out, joints)


def test_require_convertible():
    require_convertible(COCO18, BODY15)  # mid_hip from the hips
    require_convertible(BODY25, BODY15)
    with pytest.raises(InputError, match="layout body15 cannot give body25 joints: l_eye, r_eye"):
        require_convertible(BODY15, BODY25, needed=("nose", "l_eye", "r_eye"))
    with pytest.raises(InputError, match="cannot give body25 joints: .*l_small_toe"):
        require_convertible(COCO18, BODY25)
