"""Whole performances: a motion on a character, framed, rendered, with its poses and meta."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from clone.synth import get_character, render_performance, save_performance
from clone.synth.performance import body25_track
from pose_io import BODY25, InputError
from pose_io.readers import read_track
from retarget.world.skeleton import retarget_3d
from tests.clone.synth.bodies import motion_of, waving


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


def test_body25_track_copies_joints_by_name() -> None:
    xy = np.arange(2 * 3 * 2, dtype=np.float32).reshape(2, 3, 2)  # [T=2, K=3, 2]
    track = body25_track(xy, ["neck", "l_wrist", "not_a_body25_joint"], 25.0, (64, 48))
    assert track.layout == "body25" and track.fps == 25.0 and track.image_size == (64, 48)
    np.testing.assert_array_equal(track.joint("neck"), xy[:, 0])
    np.testing.assert_array_equal(track.joint("l_wrist"), xy[:, 1])
    assert (~track.missing).sum() == 2 * 2 and (track.confidence[~track.missing] == 1.0).all()


def test_save_performance_round_trip(tmp_path: Path) -> None:
    motion = motion_of(waving(5))
    skeleton, look, _ = get_character("child")
    frames, track, meta = render_performance(motion, skeleton, look, yaw=20.0, size=48, start=1, frames=3)
    done = []
    out = save_performance(tmp_path / "perf", motion, skeleton, look, yaw=20.0, size=48, start=1, frames=3,
                           extra_meta={"character": {"requested": "child"}, "demo": {"role": "x"}},
                           on_frame=done.append)
    assert done == [0, 1, 2]
    # The PNGs hold exactly the streamed frames (RGB, lossless).
    for t, image in enumerate(frames):
        png = cv2.imread(str(out / "frames" / f"frame_{t:06d}.png"))[..., ::-1]
        np.testing.assert_array_equal(png, image)
    assert read_track(out / "poses.npz").equals(track)
    saved = json.loads((out / "meta.json").read_text())
    assert saved["character"]["requested"] == "child" and saved["character"]["look"] == "child"
    assert saved["demo"] == {"role": "x"} and saved["motion"] == meta["motion"]
    assert saved["joints_outside_canvas"] == 0
    with pytest.raises(InputError, match="already exists"):  # never overwrites unasked
        save_performance(out, motion, skeleton, look, yaw=20.0, size=48, frames=3)


def test_performance_background_is_what_the_video_shows_where_the_performer_is_not() -> None:
    from clone.model.background import person_mask
    from clone.synth import performance_background
    from pose_io.measures import skeleton_height

    motion = motion_of(waving(6))
    skeleton, look, _ = get_character("average")
    frames, track, _ = render_performance(motion, skeleton, look, yaw=20.0, pitch=4.0, size=(80, 64))
    background = performance_background(look, yaw=20.0, pitch=4.0, size=(80, 64))
    assert background.shape == (64, 80, 3) and background.dtype == np.uint8
    body = track.to_layout("body15")
    radius = 0.2 * skeleton_height(body.joints, body.joint_layout)
    for frame, joints in zip(frames, body.joints):
        away = ~person_mask(joints, (64, 80), body.joint_layout, radius)
        assert away.mean() > 0.5 and np.array_equal(frame[away], background[away])
        assert not np.array_equal(frame, background)  # the performer is in the picture
    # Another view moves the floor line: another background.
    assert not np.array_equal(performance_background(look, yaw=20.0, pitch=20.0, size=(80, 64)), background)
