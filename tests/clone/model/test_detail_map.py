"""clone.model.detail_map: body31 pose maps show the face from the front, the back of the head from behind, and
the hands and feet."""

from __future__ import annotations

import numpy as np

from clone.model.canvas import pose_thickness, render_pose_map
from pose_io.draw import draw_pose
from pose_io.layouts import BODY15, BODY31
from tests.pose_io.test_details import detailed

SIZE = 200
GREY = np.array([150, 150, 150])


def _map(joints: np.ndarray) -> np.ndarray:
    return render_pose_map(joints, SIZE, BODY31)


def _head_box(joints: np.ndarray, image: np.ndarray) -> np.ndarray:
    x, y = (round(float(v)) for v in joints[BODY15.index("nose")])
    return image[y - 12:y + 12, x - 12:x + 12].reshape(-1, 3)


def _mirrored(joints: np.ndarray) -> np.ndarray:
    """The same pose seen from behind: x mirrored, so the body's left is on the image's left."""
    out = joints.copy()
    out[..., 0] = SIZE - out[..., 0]
    return out


def test_front_shows_face_features_and_back_a_grey_disc():
    front = detailed(1)[0]
    back = _mirrored(front)
    front_map, back_map = _map(front), _map(back)
    eye_white = (_head_box(front, front_map) == 255).all(axis=1).sum()
    assert eye_white > 0  # the eyes' white lines
    assert (_head_box(back, back_map) == 255).all(axis=1).sum() == 0  # no face from behind
    assert (_head_box(back, back_map) == GREY).all(axis=1).sum() > 30  # the back of the head
    assert (_head_box(front, front_map) == GREY).all(axis=1).sum() == 0


def test_hands_and_feet_are_drawn_when_known_and_body15_maps_are_unchanged():
    joints = detailed(1)[0]
    with_details = _map(joints)
    bare = joints.copy()
    bare[15:] = np.nan
    without = _map(bare)
    thumb = BODY31.index("r_thumb")
    x, y = (round(float(v)) for v in joints[thumb])
    assert with_details[y, x].any() and (with_details != without).any()
    # A body31 map without details is the body15 map plus only the face-or-back cue.
    body15 = render_pose_map(joints[:15], SIZE, BODY15)
    np.testing.assert_array_equal(body15, draw_pose(np.zeros_like(body15), joints[:15], BODY15,
                                                     thickness=pose_thickness(SIZE)))
    changed = (without != body15).any(axis=-1)
    ys, _ = np.nonzero(changed)
    neck_y = joints[BODY15.index("neck"), 1]
    assert ys.size == 0 or ys.max() <= neck_y + 2  # only around the head


def test_facing_away_by_degrees():
    front = detailed(1)[0]
    side = front.copy()
    side[BODY15.indices(["l_shoulder", "r_shoulder", "l_hip", "r_hip"]), 0] = front[BODY15.index("neck"), 0]
    side_map = _map(side)
    # Seen from the side neither the face nor the back of the head is drawn; the ears are.
    assert (_head_box(side, side_map) == 255).all(axis=1).sum() == 0
    assert (_head_box(side, side_map) == GREY).all(axis=1).sum() == 0
    assert (np.abs(_head_box(side, side_map) - np.array([255, 0, 255])).sum(axis=1) == 0).any()
