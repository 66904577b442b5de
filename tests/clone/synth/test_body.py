"""The performer: a body of shaded primitives from projected joints and a look."""

from __future__ import annotations

import numpy as np
import pytest

from clone.synth import PerformerRenderer, get_look
from retarget.world.skeleton import WORLD_JOINTS
from tests.clone.synth.bodies import SCALE, SIZE, project, renderer, standing, waving


def test_rendering_is_deterministic_and_stateless() -> None:
    poses = waving(3)
    first, _ = renderer()
    frames = [first.render(*project(p), SCALE).copy() for p in poses]
    second, _ = renderer()
    again = [second.render(*project(p), SCALE).copy() for p in poses[::-1]][::-1]
    for a, b in zip(frames, again):
        assert a.dtype == np.uint8 and a.shape == (SIZE, SIZE, 3)
        assert a.tobytes() == b.tobytes()
    assert frames[0].tobytes() != frames[-1].tobytes()


def test_background_stays_fixed_where_no_body_is() -> None:
    ren, background = renderer()
    covered = np.zeros((SIZE, SIZE), dtype=bool)
    frames, masks = [], []
    for pose in waving(6):
        frames.append(ren.render(*project(pose), SCALE).copy())
        masks.append(ren.silhouette())
        covered |= masks[-1]
        assert masks[-1].sum() > 300  # a body was drawn
    # Anti-aliased edges reach one pixel past the silhouette.
    near = covered.copy()
    for axis in (0, 1):
        for shift in (-1, 1, -2, 2):
            near |= np.roll(covered, shift, axis=axis)
    assert (~near).sum() > 0.5 * SIZE * SIZE
    for frame, mask in zip(frames, masks):
        assert (frame[~near] == background[~near]).all()
        assert (frame[mask] != background[mask]).any(axis=-1).mean() > 0.95


@pytest.mark.parametrize("yaw", [0.0, 45.0, 90.0, 180.0, 270.0])
@pytest.mark.parametrize("name", ["average", "child"])
def test_projected_joints_lie_inside_the_silhouette(yaw: float, name: str) -> None:
    ren, background = renderer(get_look(name))
    xy, depth = project(standing(), yaw)
    image = ren.render(xy, depth, SCALE)
    mask = ren.silhouette()
    for k, joint in enumerate(WORLD_JOINTS):
        x, y = np.rint(xy[k]).astype(int)
        assert mask[y, x], f"{joint} at ({x}, {y}) is outside the body (yaw {yaw})"
        assert (image[y, x] != background[y, x]).any(), joint


def test_torso_is_wide_from_the_front_and_narrow_from_the_side() -> None:
    ren, _ = renderer()
    row = int(np.rint(project(standing())[0][WORLD_JOINTS.index("neck"), 1] + 0.15 * SCALE))
    widths = []
    for yaw in (0.0, 90.0):
        pose = standing()
        for side in ("l", "r"):  # arms out of the way, in front of and behind the body's centre line
            pose[WORLD_JOINTS.index(f"{side}_elbow")] = pose[WORLD_JOINTS.index(f"{side}_shoulder")] + (0, 0.1, 0)
            pose[WORLD_JOINTS.index(f"{side}_wrist")] = pose[WORLD_JOINTS.index(f"{side}_shoulder")] + (0, 0.3, 0)
        ren.render(*project(pose, yaw), SCALE)
        widths.append(int(ren.silhouette()[row].sum()))
    front, side = widths
    assert front > 1.5 * side > 0


def test_body_shape_sets_the_thickness() -> None:
    slim, stocky = get_look("tall_long_legs"), get_look("short_stocky")
    areas = []
    for look in (slim, stocky):
        ren, _ = renderer(look)
        ren.render(*project(standing()), SCALE)
        areas.append(int(ren.silhouette().sum()))
    assert areas[1] > 1.2 * areas[0]


def test_the_head_shows_which_way_the_person_faces() -> None:
    look = get_look("average")
    ren, _ = renderer(look)
    head = WORLD_JOINTS.index("head")
    shares = []
    for yaw in (0.0, 180.0):
        xy, depth = project(standing(), yaw)
        image = ren.render(xy, depth, SCALE).astype(int)
        x, y = np.rint(xy[head]).astype(int)
        patch = image[y - 2:y + 3, x - 2:x + 3].reshape(-1, 3)
        skin = np.abs(patch - np.array(look.skin)).sum(-1)
        hair = np.abs(patch - np.array(look.hair)).sum(-1)
        shares.append(float((skin < hair).mean()))
    front, back = shares
    assert front > 0.6 and back < 0.2


def test_missing_joints_leave_their_parts_out() -> None:
    ren, _ = renderer()
    xy, depth = project(standing())
    ren.render(xy, depth, SCALE)
    full = int(ren.silhouette().sum())
    xy = xy.copy()
    for side in ("l", "r"):
        xy[WORLD_JOINTS.index(f"{side}_wrist")] = np.nan
    ren.render(xy, depth, SCALE)
    assert 0 < int(ren.silhouette().sum()) < full


def test_renderer_needs_its_joints() -> None:
    with pytest.raises(ValueError, match="head"):
        PerformerRenderer(get_look("average"), np.zeros((8, 8, 3), np.uint8), WORLD_JOINTS[:-1])
