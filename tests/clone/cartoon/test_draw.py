import numpy as np

from clone.cartoon import CartoonLook, Palette, cartoon_frames, draw_cartoon
from clone.cartoon.draw import scene
from retarget.inference.tracks import body15_track, filled_body15
from tests.figures import walking_figure


def _look(**changes) -> CartoonLook:
    defaults = {"height": 300.0, "head_radius": 30.0, "head_offset": 1.0, "shoulder_width": 60.0, "ground_y": 620.0}
    return CartoonLook(**{**defaults, **changes})


def test_frames_have_the_track_size_and_show_the_palette():
    track = body15_track(filled_body15(walking_figure(6)), 30.0, (720, 720))
    frames = list(cartoon_frames(track, _look()))
    assert len(frames) == 6
    for frame in frames:
        assert frame.shape == (720, 720, 3) and frame.dtype == np.uint8
    pal = Palette()
    colours = {tuple(c) for c in frames[0].reshape(-1, 3)}
    for colour in (pal.skin, pal.shirt, pal.pants, pal.outline, pal.background, pal.floor, pal.hair):
        assert colour in colours
    assert not np.array_equal(frames[0], frames[3])  # it moves


def test_the_character_is_drawn_where_its_joints_are():
    joints = filled_body15(walking_figure(1))[0]
    canvas = draw_cartoon(scene((720, 720), _look()), joints, _look())
    empty = scene((720, 720), _look())
    changed = np.any(canvas != empty, axis=-1)
    ys, xs = np.nonzero(changed)
    assert joints[:, 0].min() - 60 < xs.min() and xs.max() < joints[:, 0].max() + 60
    assert joints[:, 1].min() - 60 < ys.min() and ys.max() < joints[:, 1].max() + 60
    head = joints[0].round().astype(int)
    assert tuple(canvas[head[1] + 20, head[0]]) == Palette().skin  # inside the face, below the eyes


def test_a_back_view_has_no_face():
    joints = filled_body15(walking_figure(1))[0]
    back = joints.copy()
    for a, b in (("l_shoulder", "r_shoulder"), ("l_hip", "r_hip")):
        ia, ib = track_index(a), track_index(b)
        back[[ia, ib]] = back[[ib, ia]]
    look = _look(palette=Palette(eyes=(1, 2, 3)))
    front = draw_cartoon(scene((720, 720), look), joints, look)
    behind = draw_cartoon(scene((720, 720), look), back, look)
    head = joints[0].round().astype(int)
    face = (slice(head[1] - 25, head[1] + 25), slice(head[0] - 25, head[0] + 25))
    assert (front[face] == (1, 2, 3)).all(axis=-1).any()
    assert not (behind[face] == (1, 2, 3)).all(axis=-1).any()


def track_index(name: str) -> int:
    from retarget.network.preprocess import LAYOUT

    return LAYOUT.index(name)
