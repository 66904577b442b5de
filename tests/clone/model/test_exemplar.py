"""Exemplars: pose distances, the bank, the choices in training and driving, and the model file's copy."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from clone.model.exemplar import (
    LIMBS,
    ExemplarBank,
    choose_bank,
    drive_choices,
    fit_onto,
    pose_distances,
    pose_features,
    stray_limbs,
    training_choices,
    transform,
    warp_onto,
)
from tests.clone.train_ref.helpers import figure_track, render_figure


def _poses(frames: int = 24) -> np.ndarray:
    return figure_track(frames).joints  # [T, 15, 2] a figure swinging its arms, drifting sideways


def test_features_ignore_where_the_body_is_and_how_big():
    joints = _poses()[:1]
    moved = joints * 1.7 + np.array([30.0, -12.0])
    np.testing.assert_allclose(pose_features(moved), pose_features(joints), atol=1e-5)
    assert pose_distances(pose_features(moved), pose_features(joints))[0, 0] < 1e-8


def test_distances_grow_with_the_pose_and_count_joints_only_one_shows():
    joints = _poses()
    f = pose_features(joints)
    d = pose_distances(f[:1], f)[0]
    assert d[0] < 1e-8 and d[3] > d[1] > 0  # frame 3 is a quarter swing away, the arms out
    missing = f[:1].copy()
    missing[0, 4] = np.nan
    assert pose_distances(missing, f[:1])[0, 0] > 0  # the same pose with a wrist unseen is not the same
    # chunked queries give the same
    np.testing.assert_allclose(pose_distances(f, f, chunk=5), pose_distances(f, f, chunk=100))


def test_fit_lays_a_scaled_and_shifted_pose_onto_the_asked_one():
    src = _poses()[0]
    dst = src * 1.3 + np.array([7.0, -4.0])
    m = fit_onto(src, dst)
    np.testing.assert_allclose(m, [[1.3, 0, 7.0], [0, 1.3, -4.0]], atol=1e-4)
    lonely = np.full_like(src, np.nan)
    lonely[0] = 1.0
    np.testing.assert_allclose(fit_onto(lonely, dst), [[1, 0, 0], [0, 1, 0]])
    image = np.zeros((32, 32, 3), np.uint8)
    image[10, 10] = 255
    moved = warp_onto(image, np.array([[1.0, 0, 5], [0, 1.0, 3]]))
    assert moved[13, 15].max() == 255 and moved[10, 10].max() == 0


def test_the_bank_covers_the_poses_within_its_size():
    joints = _poses(48)
    frames = np.zeros((48, 8, 8, 3), np.uint8)
    usable = np.ones(48, bool)
    usable[5] = False
    small = choose_bank(frames, joints, usable, max_count=6)
    assert len(small) == 6 and 5 not in small.frames and np.all(np.diff(small.frames) > 0)
    # farthest-point sampling reaches both ends of the swing (frames 3 and 9 of each 12)
    phase = (small.frames % 12)
    assert ((phase >= 1) & (phase <= 4)).any() and ((phase >= 7) & (phase <= 10)).any()
    whole = choose_bank(frames, joints, np.ones(48, bool), max_count=100)
    assert len(whole) == 48 and whole.images is frames  # all of them: no copy


def test_training_choices_keep_away_from_the_frame_and_within_its_group():
    joints = _poses(48)
    bank = choose_bank(np.zeros((48, 8, 8, 3), np.uint8), joints, np.ones(48, bool), max_count=48)
    choices = training_choices(bank, joints, gap=6, k=3)
    assert choices.shape == (48, 3) and (choices >= 0).all()
    assert (np.abs(bank.frames[choices] - np.arange(48)[:, None]) >= 6).all()
    # the nearest outside the gap is a frame in the same pose (the swing repeats)
    f = pose_features(joints)
    nearest = pose_distances(f, bank.features)[np.arange(48), choices[:, 0]]
    assert np.all(nearest < 1e-6)
    groups = np.repeat([0, 1], 24)
    grouped = training_choices(bank, joints, gap=6, k=3, groups=groups)
    assert (groups[bank.frames[grouped]] == groups[:, None]).all()
    none = training_choices(bank, joints, gap=100, k=2)
    assert (none == -1).all()


def test_drive_choices_hold_a_choice_until_another_is_clearly_nearer():
    a, b = _poses(4)[1], _poses(4)[3]  # two poses of the swing
    bank = ExemplarBank(np.zeros((2, 8, 8, 3), np.uint8), np.stack([a, b]), np.array([0, 1]))
    # a driver wavering about half way between them, then going all the way to b
    share = np.r_[0.5 + 0.02 * (-1.0) ** np.arange(10), 1.0]
    joints = a + share[:, None, None] * (b - a)
    free = drive_choices(bank, joints, stickiness=0.0)
    held = drive_choices(bank, joints, stickiness=0.3)
    assert (np.diff(free[:10]) != 0).all()  # the nearest flicks between the two
    assert (held[:10] == held[0]).all() and held[10] == 1  # held until b is clearly nearer


def test_the_bank_goes_into_the_model_file_as_jpeg_and_comes_back():
    track = figure_track(12, 32, 32)
    frames = np.stack(render_figure(track))
    bank = choose_bank(frames, track.joints, np.ones(12, bool), max_count=4)
    stored = bank.to_storable()
    assert all(t.dtype == torch.uint8 for t in stored["jpeg"])
    back = ExemplarBank.from_storable(stored, 32)
    np.testing.assert_array_equal(back.frames, bank.frames)
    np.testing.assert_allclose(back.joints, bank.joints)
    assert np.abs(back.images.astype(int) - bank.images.astype(int)).mean() < 10  # JPEG's loss only (hard edges, 32²)
    with pytest.raises(ValueError):
        ExemplarBank.from_storable(stored, 64)
    with pytest.raises(ValueError):
        ExemplarBank.from_storable({**stored, "frames": stored["frames"][:2]}, 32)
    with pytest.raises(TypeError):
        ExemplarBank.from_storable({"jpeg": None}, 32)


def _body31(body15: np.ndarray) -> np.ndarray:
    """[31, 2]: a body15 pose with a face (eyes, ears, mouth about the nose) and no hands or feet."""
    from pose_io.layouts import get_layout

    layout = get_layout("body31")
    joints = np.full((31, 2), np.nan, np.float32)
    joints[:15] = body15
    nose = body15[0]
    for name, (dx, dy) in {"r_eye": (-2, -2), "l_eye": (2, -2), "r_ear": (-4, -1), "l_ear": (4, -1),
                           "mouth_right": (-1.5, 2.5), "mouth_left": (1.5, 2.5)}.items():
        joints[layout.index(name)] = nose + np.array([dx, dy])
    return joints


def test_the_head_is_laid_on_by_the_face_and_the_body_by_the_body():
    body = _poses(1)[0] * 0.5 + np.array([-16.0, 4.0])  # a 64² canvas
    src = _body31(body)
    image = np.zeros((64, 64, 3), np.uint8)
    nose, hip = np.round(src[0]).astype(int), np.round(src[8]).astype(int)
    image[nose[1], nose[0]] = (255, 0, 0)
    image[hip[1], hip[0]] = (0, 255, 0)
    bank = ExemplarBank(image[None], src[None], np.array([0]))
    dst = src.copy()
    dst[[0, *range(15, 21)]] += np.array([3.0, 0.0])  # the head moved 3 pixels to the side, the body kept
    out = bank.exemplar(0, dst).astype(int)
    red = np.argwhere(out[..., 0] > 100)
    assert np.abs(red.mean(0) - [nose[1], nose[0] + 3]).max() < 1.0  # the face went with the face
    assert out[hip[1], hip[0], 1] > 100  # the body stayed with the body
    # a body15 pose (no face points) lays the whole frame on by the body
    only_body = ExemplarBank(image[None], src[None, :15], np.array([0])).exemplar(0, dst[:15]).astype(int)
    assert np.abs(np.argwhere(only_body[..., 0] > 100).mean(0) - nose[::-1]).max() < 2.0


def test_the_fit_turns_a_little_and_no_more():
    src = _poses(1)[0]
    centre = src.mean(0)
    for turn, want in ((0.2, 0.2), (1.2, 0.5)):
        c, s = np.cos(turn), np.sin(turn)
        dst = (src - centre) @ np.array([[c, s], [-s, c]]) + centre
        m = fit_onto(src, dst)
        assert np.arctan2(m[1, 0], m[0, 0]) == pytest.approx(want, abs=1e-3)


def test_a_limb_that_strays_from_the_asked_pose_is_blacked_out_as_laid_on_and_as_asked():
    src = (_poses(1)[0] - _poses(1)[0].mean(0)) * 0.8 + 32.0  # a 64² canvas, arms down
    image = np.full((64, 64, 3), 200, np.uint8)
    bank = ExemplarBank(image[None], src[None], np.array([0]))
    dst = src.copy()
    shoulder = dst[5]
    dst[6], dst[7] = shoulder + [0.0, -8.0], shoulder + [0.0, -16.0]  # the left arm raised above the head
    assert stray_limbs(transform(src, fit_onto(src, dst)), dst) == [1]
    out = bank.exemplar(0, dst)
    left_arm_down, left_hand_up = np.round(src[7]).astype(int), np.round(dst[7]).astype(int)
    assert out[left_arm_down[1], left_arm_down[0]].max() == 0  # where the exemplar's own arm hangs
    assert out[left_hand_up[1], left_hand_up[0]].max() == 0  # and where the asked arm goes
    for joint in (4, 11, 14, 8):  # the other arm, the feet, the hips: as laid on
        x, y = np.round(dst[joint]).astype(int)
        assert out[y, x].min() == 200
    # the asked pose itself: nothing strays, nothing is blacked out, but for a limb dropped on purpose
    assert stray_limbs(src, src) == []
    assert bank.exemplar(0, src).min() == 200
    dropped = bank.exemplar(0, src, drop=(2,))
    knee = np.round(src[LIMBS[2][1]]).astype(int)
    assert dropped[knee[1], knee[0]].max() == 0 and (dropped == 0).all(-1).mean() < 0.2
