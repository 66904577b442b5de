"""pose_io.feet: the foot-contact cleanup on a synthetic walk with known contacts."""

import numpy as np
import pytest

from pose_io.errors import InputError
from pose_io.feet import FootLockConfig, ankle_offsets, foot_lock, swing_target, two_bone_ik
from pose_io.layouts import get_layout

BODY15 = get_layout("body15")
THIGH, SHIN = 50.0, 50.0
LEGS = {"l": 0, "r": 1}  # ANKLES order: l_ankle, r_ankle


def _knee(hip, ankle, side):
    reach = ankle - hip
    dist = np.linalg.norm(reach, axis=1)
    along = reach / dist[:, None]
    normal = np.stack([-along[:, 1], along[:, 0]], axis=1)
    cos = (THIGH**2 + dist**2 - SHIN**2) / (2 * THIGH * dist)
    return hip + THIGH * (along * cos[:, None] + side * normal * np.sqrt(1 - cos**2)[:, None])


def walk(frames: int = 60, slide: float = 0.6):
    """A walking body15 track: the hip moves right 1 px/frame, each foot alternates 20 frames of stance (on the
    ground at y 190) and 10 of swing; in stance the "retargeted" ankle slides ``slide`` px/frame. Returns
    (joints [T, 15, 2] float32, contacts [T, 2])."""
    t = np.arange(frames, dtype=np.float64)
    joints = np.zeros((frames, 15, 2))
    mid = np.stack([100 + t, np.full(frames, 100.0)], axis=1)
    joints[:, BODY15.index("mid_hip")] = mid
    joints[:, BODY15.index("neck")] = mid + [0, -60]
    joints[:, BODY15.index("nose")] = mid + [5, -75]
    for name in ("shoulder", "elbow", "wrist"):
        for s, dx in (("l", -8), ("r", 8)):
            joints[:, BODY15.index(f"{s}_{name}")] = mid + [dx, -55 + 20 * ("shoulder", "elbow", "wrist").index(name)]
    contacts = np.zeros((frames, 2), dtype=bool)
    for s, phase in (("l", 0), ("r", 15)):
        hip = mid + [(-5 if s == "l" else 5), 0]
        ankle = np.zeros((frames, 2))
        stance = ((t + phase) % 30) < 20
        plant = hip[0, 0] - 12.0
        for k in range(frames):
            if stance[k]:
                if k == 0 or not stance[k - 1]:
                    plant = hip[k, 0] - 10.0 if k == 0 else ankle[k - 1, 0]
                ankle[k] = [plant + slide * (k - _start(stance, k)), 190.0]
            else:  # swing: forward and up
                u = ((t[k] + phase) % 30 - 20) / 10.0
                ankle[k] = [ankle[k - 1, 0] + 2.5 if k else hip[k, 0], 190.0 - 15 * np.sin(np.pi * u)]
        ankle[:, 0] = np.clip(ankle[:, 0], hip[:, 0] - 40, hip[:, 0] + 40)  # keep it reachable
        joints[:, BODY15.index(f"{s}_hip")] = hip
        joints[:, BODY15.index(f"{s}_knee")] = _knee(hip, ankle, 1.0)
        joints[:, BODY15.index(f"{s}_ankle")] = ankle
        contacts[:, LEGS[s]] = stance
    return joints.astype(np.float32), contacts


def _start(stance, k):
    while k > 0 and stance[k - 1]:
        k -= 1
    return k


def bones(joints, s):
    h, k, a = (joints[:, BODY15.index(f"{s}_{n}")].astype(np.float64) for n in ("hip", "knee", "ankle"))
    return np.linalg.norm(k - h, axis=1), np.linalg.norm(a - k, axis=1), (a - h)[:, 0] * (k - h)[:, 1] - (a - h)[:, 1] * (k - h)[:, 0]


def test_held_ankles_stay_put_and_the_slide_is_gone():
    joints, contacts = walk()
    out = foot_lock(joints, contacts)
    for s, f in LEGS.items():
        x_in = joints[:, BODY15.index(f"{s}_ankle"), 0]
        x_out = out[:, BODY15.index(f"{s}_ankle"), 0]
        both = contacts[1:, f] & contacts[:-1, f]
        assert np.abs(np.diff(x_in))[both].mean() == pytest.approx(0.6, abs=1e-4)  # it did slide
        assert np.abs(np.diff(x_out))[both].max() < 1e-3  # now it holds
        # y is not forced: the leg swings about the hip, so the ankle moves only to second order
        assert np.abs(out[:, BODY15.index(f"{s}_ankle"), 1] - joints[:, BODY15.index(f"{s}_ankle"), 1]).max() < 1.0


def test_bone_lengths_and_knee_side_are_kept():
    joints, contacts = walk()
    out = foot_lock(joints, contacts)
    for s in LEGS:
        thigh0, shin0, side0 = bones(joints, s)
        thigh1, shin1, side1 = bones(out, s)
        np.testing.assert_allclose(thigh1, thigh0, atol=1e-3)
        np.testing.assert_allclose(shin1, shin0, atol=1e-3)
        assert (np.sign(side1) == np.sign(side0)).all()


def test_only_a_whole_body_shift_away_from_the_legs():
    joints, contacts = walk()
    out = foot_lock(joints, contacts)
    upper = [BODY15.index(n) for n in ("nose", "neck", "l_wrist", "r_shoulder", "mid_hip", "l_hip")]
    moved = out[:, upper] - joints[:, upper]  # [T, 6, 2]
    assert np.abs(moved[..., 1]).max() == 0.0  # never vertically
    np.testing.assert_allclose(moved[..., 0], moved[:, :1, 0].repeat(len(upper), 1), atol=1e-4)  # rigidly


def test_no_contacts_is_a_bit_for_bit_no_op():
    joints, contacts = walk()
    out = foot_lock(joints, np.zeros_like(contacts))
    assert out.dtype == joints.dtype and np.array_equal(out, joints) and out is not joints


def test_frames_with_a_missing_leg_joint_keep_that_leg():
    joints, contacts = walk()
    knee = BODY15.index("l_knee")
    joints[10:14, knee] = np.nan
    out = foot_lock(joints, contacts)
    assert np.isnan(out[10:14, knee]).all()
    legs = [BODY15.index(n) for n in ("l_hip", "l_ankle")]
    shift = out[10:14, BODY15.index("neck")] - joints[10:14, BODY15.index("neck")]  # the body's move
    np.testing.assert_allclose(out[10:14][:, legs] - joints[10:14][:, legs], shift[:, None].repeat(2, 1), atol=1e-4)
    assert np.isfinite(out[14:20, knee]).all()


def test_blends_are_continuous():
    joints, contacts = walk()
    for blend in (2, 4, 8):
        correction = foot_lock(joints, contacts, config=FootLockConfig(blend=blend, root_sigma=0)) - joints
        ankle = correction[:, BODY15.index("r_ankle"), 0].astype(np.float64)
        # smoothstep over blend + 1 steps: at most 1.5 / (blend + 1) of the correction per frame, plus the slide
        assert np.abs(np.diff(ankle)).max() <= 1.5 / (blend + 1) * np.abs(ankle).max() + 0.6 + 1e-3


def test_ankle_offsets_known_values():
    x = np.arange(12, dtype=np.float64)
    ankle = np.stack([x, np.zeros(12)], axis=1)
    contact = np.zeros(12, dtype=bool)
    contact[4:7] = True  # x 4, 5, 6: held at 5
    off = ankle_offsets(ankle, contact, blend=2)
    np.testing.assert_allclose(off[4:7, 0], [1.0, 0.0, -1.0])
    assert (off[:, 1] == 0).all() and (off[:2] == 0).all() and (off[9:] == 0).all()
    w = 1 - 1 / 3  # smoothstep(2/3) at one frame out
    np.testing.assert_allclose(off[3, 0], w * w * (3 - 2 * w) * 1.0)
    np.testing.assert_allclose(off[7, 0], w * w * (3 - 2 * w) * -1.0)


def test_two_bone_ik_and_swing_known_values():
    hip, knee, ankle = np.array([[0.0, 0.0]]), np.array([[3.0, 4.0]]), np.array([[0.0, 8.0]])  # 5 + 5, bent right
    new_knee, new_ankle = two_bone_ik(hip, knee, ankle, np.array([[6.0, 0.0]]), np.array([-1.0]))
    np.testing.assert_allclose(new_ankle, [[6.0, 0.0]])
    np.testing.assert_allclose(new_knee, [[3.0, -4.0]], atol=1e-12)  # the leg turned -90°, the knee with it
    _, far = two_bone_ik(hip, knee, ankle, np.array([[0.0, 20.0]]), np.array([1.0]))
    np.testing.assert_allclose(far, [[0.0, 10.0]])  # out of reach: as far as the leg goes
    np.testing.assert_allclose(swing_target(hip, ankle, np.array([8.0])), [[8.0, 0.0]], atol=1e-12)


def test_contacts_of_another_length_are_refused():
    joints, contacts = walk(slide=0.0)
    with pytest.raises(InputError):
        foot_lock(joints, contacts[:-1])
