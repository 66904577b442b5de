"""The synthetic-performer renderer: rasteriser, body, looks and whole performances."""

from __future__ import annotations

import json

import numpy as np
import pytest

from pose_io import BODY25, InputError
from retarget.world.appearance import NAMED_LOOKS, Look, get_character, get_look, look_from_seed
from retarget.world.render import (
    Paint,
    PerformerRenderer,
    Rasterizer,
    make_background,
    render_performance,
)
from retarget.world.skeleton import NAMED_CHARACTERS, WORLD_JOINTS, Motion3D, normalise_placement, retarget_3d

SIZE = 128
SCALE = 0.4 * SIZE  # pixels per metre

# A standing adult (metres, Y up, facing +Z), by world joint name.
STANDING = {
    "head": (0.0, 1.62, 0.0), "nose": (0.0, 1.58, 0.1), "neck": (0.0, 1.42, 0.0),
    "r_shoulder": (-0.19, 1.42, 0.0), "l_shoulder": (0.19, 1.42, 0.0),
    "r_elbow": (-0.24, 1.14, -0.02), "l_elbow": (0.24, 1.14, 0.0),
    "r_wrist": (-0.30, 0.90, 0.1), "l_wrist": (0.27, 0.88, 0.03),
    "mid_hip": (0.0, 0.95, 0.0), "r_hip": (-0.1, 0.95, 0.0), "l_hip": (0.1, 0.95, 0.0),
    "r_knee": (-0.11, 0.52, 0.06), "l_knee": (0.1, 0.52, 0.02),
    "r_ankle": (-0.12, 0.09, -0.02), "l_ankle": (0.1, 0.09, -0.02),
    "r_big_toe": (-0.14, 0.02, 0.15), "l_big_toe": (0.12, 0.02, 0.15),
}


def standing() -> np.ndarray:
    """[18, 3] the standing body in ``WORLD_JOINTS`` order."""
    return np.array([STANDING[n] for n in WORLD_JOINTS], dtype=np.float64)


def project(points: np.ndarray, yaw_deg: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Turn [..., 3] points by ``yaw`` about Y, project orthographically: (xy [..., 2] px, depth [...] m)."""
    a = np.deg2rad(yaw_deg)
    rot = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
    p = points @ rot.T
    xy = np.stack([SIZE / 2 + SCALE * p[..., 0], 0.92 * SIZE - SCALE * p[..., 1]], axis=-1)
    return xy, 5.0 - p[..., 2]


def waving(frames: int) -> np.ndarray:
    """[T, 18, 3] the standing body raising its right arm sideways."""
    out = np.repeat(standing()[None], frames, axis=0)
    sh = out[:, WORLD_JOINTS.index("r_shoulder")]
    for t in range(frames):
        angle = np.deg2rad(20 + 110 * t / max(frames - 1, 1))
        arm = np.array([-np.sin(angle), -np.cos(angle), 0.0])
        out[t, WORLD_JOINTS.index("r_elbow")] = sh[t] + 0.3 * arm
        out[t, WORLD_JOINTS.index("r_wrist")] = sh[t] + 0.55 * arm
    return out


def renderer(look: Look | None = None) -> tuple[PerformerRenderer, np.ndarray]:
    look = look or get_look("average")
    background = make_background(SIZE, SIZE, look.backdrop, 0.8 * SIZE)
    return PerformerRenderer(look, background, WORLD_JOINTS), background


# ------------------------------------------------------------------ rasteriser


@pytest.mark.parametrize("blue_first", [False, True])
@pytest.mark.parametrize("blue_depth", [4.0, 6.0])
def test_nearer_capsule_hides_the_one_behind(blue_first: bool, blue_depth: float) -> None:
    grey = np.full((64, 64, 3), 128, dtype=np.uint8)
    ras = Rasterizer(grey)
    # End points in metres at 100 px/m: a horizontal red and a vertical blue capsule crossing at (32, 32).
    red = ([0.10, 0.32, 5.0], [0.54, 0.32, 5.0], ((1.0, Paint.solid((255, 0, 0))),))
    blue = ([0.32, 0.10, blue_depth], [0.32, 0.54, blue_depth], ((1.0, Paint.solid((0, 0, 255))),))
    for pa, pb, bands in (blue, red) if blue_first else (red, blue):
        ras.capsule(np.array(pa), np.array(pb), 0.06, 0.06, 100.0, bands)  # 6 px radius
    image = ras.image()
    centre = image[32, 32].astype(int)
    if blue_depth < 5.0:
        assert centre[2] > 60 and centre[0] == 0
    else:
        assert centre[0] > 60 and centre[2] == 0
    # Away from the crossing each capsule shows its own colour, shaded but not mixed.
    assert image[32, 14, 0] > 60 and image[32, 14, 2] == 0
    assert image[14, 32, 2] > 60 and image[14, 32, 0] == 0
    assert (image[2, 2] == 128).all()


def test_rasterizer_rejects_a_bad_background() -> None:
    with pytest.raises(ValueError, match="uint8"):
        Rasterizer(np.zeros((8, 8, 3), dtype=np.float32))


# ------------------------------------------------------------------ body


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


def test_background_depends_on_the_seed_only() -> None:
    look_a, look_b = get_look("average"), get_look("child")
    a = make_background(64, 48, look_a.backdrop, 36.0)
    assert a.shape == (48, 64, 3) and a.dtype == np.uint8
    assert a.tobytes() == make_background(64, 48, look_a.backdrop, 36.0).tobytes()
    assert a.tobytes() != make_background(64, 48, look_b.backdrop, 36.0).tobytes()


# ------------------------------------------------------------------ looks and characters


def test_looks_from_seeds_are_reproducible_and_varied() -> None:
    assert look_from_seed(3) == look_from_seed(3)
    looks = [look_from_seed(s) for s in range(12)]
    assert len({look.top for look in looks}) > 8
    assert len({look.shape.thigh for look in looks}) > 8
    assert get_look("5") == look_from_seed(5)


def test_every_named_character_has_a_look() -> None:
    for name in NAMED_CHARACTERS:
        assert get_look(name).name == name
    assert set(NAMED_LOOKS) <= set(NAMED_CHARACTERS)
    # A name without a designed look still gets one, the same every time.
    assert get_look("somebody_new") == get_look("somebody_new")
    assert get_look("somebody_new").name == "somebody_new"


def test_get_character_by_name_or_seed() -> None:
    skeleton, look, seed = get_character("child")
    assert skeleton is NAMED_CHARACTERS["child"] and look.name == "child" and seed is None
    skeleton, look, seed = get_character("42")
    assert seed == 42 and skeleton.name == "seed:42"
    assert get_character(42)[0] == skeleton
    with pytest.raises(InputError, match="tall_long_legs"):
        get_character("giant")


def test_look_rejects_unknown_styles() -> None:
    with pytest.raises(ValueError, match="sleeves"):
        Look(sleeves="puffy")


# ------------------------------------------------------------------ performances


def motion_of(positions: np.ndarray) -> Motion3D:
    return Motion3D(normalise_placement(positions).astype(np.float32), 30.0, "wave")


def test_render_performance_frames_track_and_meta() -> None:
    motion = motion_of(waving(8))
    skeleton, look, _ = get_character("short_stocky")
    frames, track, meta = render_performance(motion, skeleton, look, yaw=30.0, pitch=5.0, size=96, start=2, frames=4)
    assert iter(frames) is frames  # a lazy stream: long clips never sit in memory
    images = list(frames)
    assert len(images) == 4 and all(im.shape == (96, 96, 3) and im.dtype == np.uint8 for im in images)
    assert track.layout == "body25" and track.num_frames == 4 and track.image_size == (96, 96)
    for name in ("r_eye", "l_ear", "l_small_toe", "r_heel"):
        assert track.missing[:, BODY25.index(name)].all()
    for name in ("nose", "neck", "mid_hip", "l_big_toe", "r_big_toe", "r_wrist"):
        assert not track.missing[:, BODY25.index(name)].any()
    # The framing rule puts the ground under the clip's first root at (W/2, 0.9 H).
    ground = 0.5 * (track.joint("l_big_toe")[0] + track.joint("r_big_toe")[0])
    assert abs(ground[1] - 0.9 * 96) < 3
    assert meta["motion"]["start"] == 2 and meta["motion"]["frames"] == 4
    assert meta["character"]["bone_lengths_m"] == skeleton.as_dict()
    assert meta["camera"]["yaw_deg"] == 30.0 and meta["camera"]["pitch_deg"] == 5.0
    json.dumps(meta)


def test_rendering_a_motion_equals_rendering_it_already_retargeted() -> None:
    # The ground truth of a cloning run: the driver's motion on the reference's skeleton.
    motion = motion_of(waving(6))
    skeleton, look, _ = get_character("tall_long_legs")
    frames_a, track_a, _ = render_performance(motion, skeleton, look, yaw=-40.0, size=64)
    frames_b, track_b, _ = render_performance(retarget_3d(motion, skeleton), skeleton, look, yaw=-40.0, size=64)
    assert track_a.equals(track_b, atol=1e-3)
    for a, b in zip(frames_a, frames_b):
        assert np.abs(a.astype(int) - b.astype(int)).max() <= 2


def test_render_performance_checks_its_frame_range() -> None:
    motion = motion_of(waving(4))
    skeleton, look, _ = get_character("average")
    with pytest.raises(ValueError, match="outside"):
        render_performance(motion, skeleton, look, 0.0, start=4)
    with pytest.raises(ValueError, match="outside"):
        render_performance(motion, skeleton, look, 0.0, start=1, frames=4)
