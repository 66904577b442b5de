"""Known-value tests of the report's measures on tiny hand-made tracks and frames."""

from __future__ import annotations

import math

import numpy as np
import pytest

from clone import metrics
from pose_io import BODY15, InputError, PoseTrack, measures

# A standing body15 skeleton (x right, y down) whose bones are easy to add up.
_STAND = {
    "nose": (100, 40), "neck": (100, 60), "r_shoulder": (85, 60), "r_elbow": (80, 90), "r_wrist": (78, 120),
    "l_shoulder": (115, 60), "l_elbow": (120, 90), "l_wrist": (122, 120), "mid_hip": (100, 120),
    "r_hip": (92, 120), "r_knee": (92, 160), "r_ankle": (92, 200), "l_hip": (108, 120), "l_knee": (108, 160),
    "l_ankle": (108, 200),
}  # fmt: skip
# nose-neck 20 + neck-mid_hip 60 + hip-knee 40 + knee-ankle 40
HEIGHT = 160.0


def stand(frames: int = 10) -> np.ndarray:
    """[T, 15, 2] the standing skeleton repeated."""
    pose = np.array([_STAND[n] for n in BODY15.joints], dtype=np.float64)
    return np.repeat(pose[None], frames, axis=0)


def test_self_comparison_is_perfect():
    joints = stand(12)
    ref = measures.reference_limb_lengths(joints)
    scores = metrics.pose_scores(joints, (200, 240), ref, HEIGHT)
    assert scores.summary["limb_error_pct"] == 0.0
    assert scores.summary["jitter_pct"] == 0.0
    assert scores.summary["outside_share"] == 0.0
    assert scores.summary["foot_slide_px"] == 0.0
    gt = metrics.gt_pose_scores(joints, joints, HEIGHT)
    facing = gt.summary.pop("facing_share")
    assert gt.summary == {"pose_mse": 0.0, "pose_rmse_pct": 0.0, "pck_0.05": 1.0, "pck_0.1": 1.0, "root_rmse_pct": 0.0}
    assert np.all(gt.per_frame["pck_0.1"] == 1.0)
    assert math.isnan(facing)  # seen from the front: no side to face


def test_uniform_scale_gives_known_limb_error():
    joints = stand(5)
    ref = measures.reference_limb_lengths(joints)
    scaled = (joints - joints[:, :1]) * 1.25 + joints[:, :1]  # 25 % larger around the nose
    per_frame, errors = metrics.limb_error(scaled, ref, HEIGHT)
    expected_per_limb = 0.25 * ref / HEIGHT * 100.0
    np.testing.assert_allclose(errors, np.broadcast_to(expected_per_limb, errors.shape), rtol=1e-12)
    np.testing.assert_allclose(per_frame, expected_per_limb.mean(), rtol=1e-12)
    scores = metrics.pose_scores(scaled, (400, 400), ref, HEIGHT)
    assert scores.summary["limb_error_pct"] == pytest.approx(expected_per_limb.mean(), rel=1e-12)
    # the leg: 40 px bones, 10 px too long each -> 6.25 % of 160 px
    assert scores.details["limb_error_pct_per_limb"]["r_knee-r_ankle"] == pytest.approx(6.25)


def test_missing_limb_is_left_out_not_counted_as_error():
    joints = stand(4)
    ref = measures.reference_limb_lengths(joints)
    joints[1, BODY15.index("l_wrist")] = np.nan
    per_frame, errors = metrics.limb_error(joints, ref, HEIGHT)
    assert np.isnan(errors[1]).sum() == 1 and per_frame[1] == 0.0
    joints[2] = np.nan
    per_frame, _ = metrics.limb_error(joints, ref, HEIGHT)
    assert np.isnan(per_frame[2])


def test_sliding_foot_gives_known_slide():
    joints = stand(40)
    right = BODY15.index("r_ankle")
    joints[:, right, 0] += 2.0 * np.arange(40)  # slides 2 px per frame on the ground
    slide, contact = metrics.foot_slide(joints, HEIGHT, BODY15, window=9)
    assert contact.all()
    assert np.isnan(slide[0]).all()
    np.testing.assert_allclose(slide[1:, measures.ANKLES.index("r_ankle")], 2.0)
    np.testing.assert_allclose(slide[1:, measures.ANKLES.index("l_ankle")], 0.0)
    ref = measures.reference_limb_lengths(stand())
    scores = metrics.pose_scores(joints, (400, 400), ref, HEIGHT, window=9)
    assert scores.summary["foot_slide_px"] == pytest.approx(1.0)  # mean over both ankles
    assert scores.summary["foot_slide_pct"] == pytest.approx(1.0 / HEIGHT * 100)
    np.testing.assert_allclose(scores.per_frame["foot_slide_pct"][1:], 1.0 / HEIGHT * 100)


def test_lifted_foot_is_not_in_contact():
    joints = stand(50)
    right = BODY15.index("r_ankle")
    # planted for 10 frames, a step (up, forward, down) over 30, planted again for 10
    joints[10:40, right, 1] -= 30.0 * np.sin(np.linspace(0, np.pi, 30))
    joints[10:40, right, 0] += 3.0 * np.arange(30)
    joints[40:, right, 0] += 90.0
    slide, contact = metrics.foot_slide(joints, HEIGHT, BODY15, window=31)
    col = measures.ANKLES.index("r_ankle")
    assert contact[:10, col].all() and contact[41:, col].all()
    assert not contact[12:38, col].any()
    np.testing.assert_allclose(slide[1:10, col], 0.0)
    np.testing.assert_allclose(slide[42:, col], 0.0)
    assert np.isnan(slide[12:38, col]).all()
    assert contact[:, measures.ANKLES.index("l_ankle")].all()


def test_constant_velocity_has_zero_jitter_and_a_kick_has_known_jitter():
    joints = stand(20) + np.arange(20)[:, None, None] * np.array([3.0, -1.5])
    acc = metrics.jitter(joints)
    assert np.isnan(acc[0]).all() and np.isnan(acc[-1]).all()
    np.testing.assert_allclose(acc[1:-1], 0.0, atol=1e-9)
    joints[10, 0] += [3.0, 4.0]  # one joint jumps out 5 px in one frame: accelerations 5, 10, 5
    acc = metrics.jitter(joints)
    np.testing.assert_allclose(acc[9:12, 0], [5.0, 10.0, 5.0], atol=1e-9)
    ref = measures.reference_limb_lengths(stand())
    scores = metrics.pose_scores(joints, (10_000, 10_000), ref, HEIGHT)
    assert scores.summary["jitter_pct"] == pytest.approx(20.0 / (18 * 15) / HEIGHT * 100)


def test_outside_share():
    joints = stand(2)
    joints[0, :3, 0] = -5.0  # three joints left of the image
    joints[1, 0] = np.nan
    out = metrics.outside_frame(joints, (200, 240))
    assert np.nansum(out[0]) == 3 and np.isnan(out[1, 0])
    scores = metrics.pose_scores(joints, (200, 240), measures.reference_limb_lengths(stand()), HEIGHT)
    np.testing.assert_allclose(scores.per_frame["outside_share"], [3 / 15, 0.0])
    assert scores.summary["outside_share"] == pytest.approx(3 / 29)


def test_gt_pose_errors_known_values():
    gt = stand(4)
    pred = gt.copy()
    pred[:, :, 0] += 0.06 * HEIGHT  # every joint 6 % of the height to the right: the right pose, misplaced
    scores = metrics.gt_pose_scores(pred, gt, HEIGHT)
    assert scores.summary["pose_rmse_pct"] == pytest.approx(0.0, abs=1e-12)
    assert scores.summary["pose_mse"] == pytest.approx(0.0, abs=1e-12) and scores.summary["pck_0.05"] == 1.0
    assert scores.summary["root_rmse_pct"] == pytest.approx(6.0)
    np.testing.assert_allclose(scores.per_frame["root_rmse_pct"], 6.0)
    legs = [BODY15.index(n) for n in ("r_knee", "r_ankle", "l_knee", "l_ankle")]
    pred[:, legs, 1] += 0.06 * HEIGHT  # longer legs: 4 of the 14 MidHip-aligned joints 6 % off, in y
    scores = metrics.gt_pose_scores(pred, gt, HEIGHT)
    assert scores.summary["pose_mse"] == pytest.approx(0.06**2 * 4 / 28)  # over joints and both coordinates
    assert scores.summary["pose_rmse_pct"] == pytest.approx(6.0 * np.sqrt(4 / 14))
    assert scores.summary["pck_0.05"] == pytest.approx(10 / 14) and scores.summary["pck_0.1"] == 1.0
    pred[0, legs] = gt[0, legs] + [0.06 * HEIGHT, 0.0]  # first frame: the legs right again
    pred[1, BODY15.index("nose")] = np.nan  # a missing joint is left out
    scores = metrics.gt_pose_scores(pred, gt, HEIGHT)
    assert scores.per_frame["pck_0.05"][0] == 1.0 and scores.per_frame["pck_0.05"][2] == pytest.approx(10 / 14)
    assert scores.summary["pck_0.05"] == pytest.approx((14 + 9 + 10 + 10) / 55)
    with pytest.raises(InputError, match="does not match"):
        metrics.gt_pose_scores(pred[:3], gt, HEIGHT)
    with pytest.raises(InputError, match="ground-truth poses: .*height must be positive"):
        metrics.gt_pose_scores(pred, gt, 0.0)


def test_gt_facing_share_counts_frames_facing_the_true_side():
    gt = stand(4)
    nose, neck = BODY15.index("nose"), BODY15.index("neck")
    gt[:, nose, 0] = gt[:, neck, 0] - 0.04 * HEIGHT  # seen from its left: faces image-left
    gt[3, nose, 0] = gt[3, neck, 0]  # frame 3 seen from the front: no side, left out
    mirrored = gt.copy()
    mirrored[:, nose, 0] = gt[:, neck, 0] + 0.04 * HEIGHT  # the other side
    mirrored[0, nose, 0] = gt[0, nose, 0]  # ...except in frame 0
    scores = metrics.gt_pose_scores(mirrored, gt, HEIGHT)
    assert scores.summary["facing_share"] == pytest.approx(1 / 3)
    np.testing.assert_array_equal(scores.per_frame["facing_share"][:3], [1.0, 0.0, 0.0])
    assert np.isnan(scores.per_frame["facing_share"][3])
    assert metrics.gt_pose_scores(gt, gt, HEIGHT).summary["facing_share"] == 1.0


def test_person_box_margin_and_edges():
    joints = np.array([[50.0, 20.0], [70.0, 120.0], [np.nan, np.nan]])
    assert metrics.person_box(joints, (200, 200), margin=0.1) == (40, 10, 80, 130)
    assert metrics.person_box(joints, (60, 125), margin=0.1) == (40, 10, 60, 125)
    assert metrics.person_box(np.full((3, 2), np.nan), (60, 60)) is None
    # a single joint in a corner still gives a 7 x 7 box inside the image
    assert metrics.person_box(np.array([[0.0, 59.0]]), (60, 60)) == (0, 53, 7, 60)


def test_frame_scores_identical_and_noisy():
    rng = np.random.default_rng(0)
    gt = rng.integers(0, 256, (3, 64, 48, 3), dtype=np.uint8)
    joints = np.repeat(np.array([[[10.0, 10.0], [30.0, 50.0]]]), 3, axis=0)
    same = metrics.frame_scores(gt, gt.copy(), joints)
    assert same.summary["ssim"] == pytest.approx(1.0) and same.summary["ssim_crop"] == pytest.approx(1.0)
    assert math.isinf(same.summary["psnr"]) and math.isinf(same.summary["psnr_crop"])
    noisy = gt.astype(np.int16)
    noisy[:, 5:55, 5:40] += 10  # only inside the person's box
    noisy = np.clip(noisy, 0, 255).astype(np.uint8)
    scores = metrics.frame_scores(noisy, gt, joints)
    mse = np.mean((noisy[0].astype(float) - gt[0]) ** 2)
    assert scores.per_frame["psnr"][0] == pytest.approx(10 * np.log10(255**2 / mse))
    assert scores.summary["ssim"] < 1.0
    assert scores.summary["psnr_crop"] < scores.summary["psnr"]  # the change is concentrated in the crop
    whole = metrics.frame_scores(noisy, gt)
    assert set(whole.summary) == {"ssim", "psnr"}
    with pytest.raises(InputError, match="ground-truth frames"):
        metrics.frame_scores(noisy[:2], gt)


def test_background_psnr_counts_only_pixels_outside_the_person():
    rng = np.random.default_rng(1)
    gt = rng.integers(20, 230, (2, 64, 48, 3), dtype=np.uint8)
    joints = np.repeat(np.array([[[10.0, 10.0], [30.0, 50.0]]]), 2, axis=0)
    box = metrics.person_box(joints[0], (48, 64))  # (7, 4, 33, 56) with the default margin
    x0, y0, x1, y1 = box
    inside = gt.copy()
    inside[:, y0:y1, x0:x1] = 0  # a wrong person, an exact background
    assert math.isinf(metrics.frame_scores(inside, gt, joints).summary["psnr_background"])
    shifted = gt.copy()
    shifted[0, :2] += 10  # rows 0-1 lie above the box: 2 rows x 48 px x 3 values off by 10, in frame 0 only
    outside = 64 * 48 * 3 - (y1 - y0) * (x1 - x0) * 3
    scores = metrics.frame_scores(shifted, gt, joints)
    pooled = 2 * 48 * 3 * 100 / (2 * outside)
    assert scores.summary["psnr_background"] == pytest.approx(10 * np.log10(255**2 / pooled))
    assert math.isinf(scores.per_frame["psnr_background"][1])


def test_evaluate_track_uses_fps_window_and_gt_layout():
    joints = stand(30)
    track = PoseTrack(joints, np.ones(joints.shape[:2]), 30.0, (200, 240), "body15")
    body25 = np.full((30, 25, 2), np.nan)
    body25[:, :15] = joints
    gt = PoseTrack(body25, np.isfinite(body25[..., 0]).astype(float), 30.0, (200, 240), "body25")
    scores = metrics.evaluate_track(track, measures.reference_limb_lengths(joints), HEIGHT, gt)
    assert scores.summary["pose_mse"] == 0.0 and scores.summary["limb_error_pct"] == 0.0
    assert scores.summary["root_rmse_pct"] == 0.0
    assert set(metrics.METRICS) >= set(scores.summary)
    shifted = track.replace(joints=joints + [HEIGHT * 0.1, 0.0])
    moved = metrics.evaluate_track(shifted, measures.reference_limb_lengths(joints), HEIGHT, gt)
    assert moved.summary["pose_rmse_pct"] == pytest.approx(0.0, abs=1e-9)  # placement is its own row
    assert moved.summary["root_rmse_pct"] == pytest.approx(10.0)
    assert metrics.contact_window(30.0) == 31 and metrics.contact_window(25.0) == 25
    with pytest.raises(InputError, match="frames"):
        metrics.evaluate_track(track, measures.reference_limb_lengths(joints), HEIGHT, gt.frames(0, 10))


def test_limb_never_seen_in_reference_is_left_out():
    joints = stand(3)
    joints[:, BODY15.index("l_wrist")] = np.nan
    ref = measures.reference_limb_lengths(joints)
    assert np.isnan(ref[BODY15.limbs.index(("l_elbow", "l_wrist"))]) and np.isfinite(ref).sum() == 13
    per_frame, _ = metrics.limb_error(stand(3), ref, HEIGHT)
    np.testing.assert_allclose(per_frame, 0.0)



def test_flicker_is_the_mean_change_inside_the_pose_box():
    from clone.metrics import FlickerMeter

    pose = np.array([[10.0, 10.0], [20.0, 30.0]])  # box x 7-23, y 7-33 with the 15 % margin
    still = np.zeros((40, 40, 3), np.uint8)
    lit = still.copy()
    lit[:, :] = 30  # every pixel changes by 30 levels
    outside = still.copy()
    outside[:, 30:] = 200  # only outside the box
    meter = FlickerMeter()
    for frame in (still, lit, lit, outside):
        meter.add(frame, pose)
    per_frame = meter.per_frame()
    assert np.isnan(per_frame[0])
    np.testing.assert_allclose(per_frame[1:], [30.0, 0.0, 30.0])  # back to black inside the box
    assert meter.value() == pytest.approx(20.0)
    meter.add(still, None)  # no pose: not measured
    assert np.isnan(meter.per_frame()[-1]) and meter.value() == pytest.approx(20.0)
