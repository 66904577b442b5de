"""stage: a driven track is kept on the part of the frame the reference occupied, smoothly and shape-preserving."""

from __future__ import annotations

import logging

import numpy as np
import pytest

from clone.drive.stage import (
    StageConfig,
    StageFit,
    fit_interval,
    fit_to_stage,
    reference_stage,
    start_on_reference,
)
from pose_io import BODY15, PoseTrack
from pose_io.measures import foot_points

# A standing body15 figure, 1 unit from the mid-hip to the ankles' level below it (x right, y down).
_BASE = np.array(
    [[0, -0.62], [0, -0.5], [-0.12, -0.48], [-0.16, -0.3], [-0.17, -0.12], [0.12, -0.48], [0.16, -0.3],
     [0.17, -0.12], [0, 0], [-0.07, 0], [-0.08, 0.2], [-0.08, 0.4], [0.07, 0], [0.08, 0.2], [0.08, 0.4]])
SIZE = (640, 480)


def figure(root_x: np.ndarray, foot_y: np.ndarray, height: np.ndarray | float = 100.0) -> PoseTrack:
    """A figure per frame, its root at ``root_x``, its ankles at ``foot_y``, ``height`` px from nose to ankles."""
    root_x, foot_y = np.asarray(root_x, float), np.asarray(foot_y, float)
    height = np.broadcast_to(np.asarray(height, float), root_x.shape)
    t = np.arange(len(root_x))
    j = np.repeat(_BASE[None], len(root_x), axis=0)  # [T, J, 2]
    j[:, BODY15.index("r_wrist"), 0] += 0.1 * np.sin(t / 3.0)  # some motion of the limbs
    j[:, BODY15.index("l_ankle"), 0] += 0.05 * np.sin(t / 4.0)
    xy = j / 1.02 * height[:, None, None]  # [T, J, 2]: 1.02 units from the nose to the ankles
    xy[..., 0] += root_x[:, None]
    xy[..., 1] += (foot_y - 0.4 / 1.02 * height)[:, None]
    return PoseTrack(xy.astype(np.float32), np.ones(xy.shape[:2], np.float32), 25.0, SIZE, "body15")


def reference(frames: int = 60) -> PoseTrack:
    """Walks 200..300 px across and 300..360 px in depth, 100 px tall far away and 120 px close."""
    s = 0.5 - 0.5 * np.cos(np.linspace(0, 2 * np.pi, frames))
    foot = 300 + 60 * s
    return figure(200 + 100 * s, foot, 100 + 20 * (foot - 300) / 60)


def root_x(track: PoseTrack) -> np.ndarray:
    return track.joint("mid_hip")[:, 0].astype(np.float64)


def foot_y(track: PoseTrack) -> np.ndarray:
    return foot_points(track.joints, track.joint_layout)[:, 1]


def test_a_track_on_the_stage_is_left_alone():
    ref = reference()
    inside = figure(np.linspace(220, 280, 40), np.linspace(310, 350, 40), 110.0)
    for track in (ref, inside):
        out, fit = fit_to_stage(track, ref)
        assert out is track and not fit.moved and fit.share == 0.0 and fit.reason == ""
    stage = reference_stage(ref)
    assert 200 <= stage.x_range[0] < 203 and 297 < stage.x_range[1] <= 300
    assert 300 <= stage.foot_range[0] < 302 and 358 < stage.foot_range[1] <= 360


def test_a_track_walking_out_sideways_is_shifted_back_without_changing_its_motion():
    ref = reference()
    walk = figure(np.linspace(250, 320, 50), np.full(50, 330.0), 110.0)  # ends 20 px past the stage's right edge
    out, fit = fit_to_stage(walk, ref)
    stage = reference_stage(ref)
    assert fit.moved and 0.2 < fit.share < 0.4 and fit.x_scale == 1.0
    assert fit.x_shift == pytest.approx(stage.x_range[1] + stage.margin - 320)  # just back onto the stage
    # A pure shift: every joint moves by the same amount in every frame.
    np.testing.assert_allclose(out.joints - walk.joints, np.broadcast_to([fit.x_shift, 0.0], walk.joints.shape),
                               atol=1e-3)


def test_a_wider_walk_is_compressed_smoothly_into_the_range():
    ref = reference()
    walk = figure(np.linspace(0, 600, 80), np.full(80, 330.0), 110.0)
    out, fit = fit_to_stage(walk, ref)
    stage = reference_stage(ref)
    x = root_x(out)
    assert fit.share > 0.8 and fit.x_scale < 0.2
    assert stage.x_range[0] - stage.margin - 1e-3 <= x.min() and x.max() <= stage.x_range[1] + stage.margin + 1e-3
    # One affine map of the whole trajectory: a constant velocity stays constant (no kink where a clamp starts).
    np.testing.assert_allclose(np.diff(x, 2), 0.0, atol=1e-3)
    # The body moves rigidly with its root: joints relative to the root are unchanged.
    relative = [t.joints - t.joint("mid_hip")[:, None] for t in (out, walk)]  # [T, J, 2] each
    np.testing.assert_allclose(*relative, atol=1e-3)


def test_walking_towards_the_camera_is_kept_in_depth_with_the_references_change_of_size():
    ref = reference()
    foot = np.linspace(330, 420, 60)  # 60 px past the closest position the reference reached
    walk = figure(np.full(60, 250.0), foot, 110.0 + 20 * (foot - 330) / 60)
    out, fit = fit_to_stage(walk, ref)
    stage = reference_stage(ref)
    new_foot = foot_y(out)
    assert fit.moved and fit.foot_scale < 1.0 and fit.x_scale == 1.0 and fit.x_shift == 0.0
    assert stage.foot_range[0] - stage.margin - 1e-3 <= new_foot.min()
    assert new_foot.max() <= stage.foot_range[1] + stage.margin + 1e-3
    np.testing.assert_allclose(np.diff(new_foot, 2), 0.0, atol=1e-3)  # linear in, linear out
    # Every frame's pose is the old one scaled about the feet by the reference's height ratio (EDN).
    k = stage.height(new_foot) / stage.height(foot)
    anchor = np.stack([root_x(walk), foot], axis=-1)[:, None]  # [T, 1, 2]
    new_anchor = np.stack([root_x(out), new_foot], axis=-1)[:, None]
    np.testing.assert_allclose(out.joints - new_anchor, k[:, None, None] * (walk.joints - anchor), atol=1e-3)
    assert (k < 1).all() and np.all(np.diff(k) < 1e-9)  # farther away = smaller, smoothly
    # The moved figure has about the size the reference had at its new foot position (within the margin).
    ref_height_at = 100 + 20 * (new_foot - 300) / 60
    height = out.joint("r_ankle")[:, 1] - out.joint("nose")[:, 1]
    assert np.abs(height / ref_height_at - 1).max() < 0.12


def test_missing_joints_stay_missing_and_a_missing_root_is_interpolated():
    ref = reference()
    walk = figure(np.linspace(0, 600, 40), np.linspace(330, 420, 40), 110.0)
    joints, conf = walk.joints.copy(), walk.confidence.copy()
    conf[5:9, BODY15.index("mid_hip")] = 0  # the root is gone for a few frames
    conf[::3, BODY15.index("l_wrist")] = 0
    conf[20, :] = 0  # a frame without anybody
    holes = PoseTrack(joints, conf, walk.fps, walk.image_size, walk.layout)
    out, fit = fit_to_stage(holes, ref)
    full, _ = fit_to_stage(walk, ref)
    assert fit.moved and np.array_equal(out.missing, holes.missing)
    seen = ~holes.missing
    np.testing.assert_allclose(out.joints[seen], full.joints[seen], atol=0.5)


@pytest.mark.parametrize("case", ["no ankles", "one frame", "no root anywhere in the track"])
def test_no_stage_leaves_the_track_as_it_is_and_says_why(case, caplog):
    ref, walk = reference(), figure(np.linspace(0, 600, 20), np.full(20, 330.0))
    if case == "no ankles":
        conf = ref.confidence.copy()
        conf[:, BODY15.indices(("l_ankle", "r_ankle"))] = 0
        ref = ref.replace(confidence=conf)
    elif case == "one frame":
        ref = ref.frames(0, 1)
    else:
        conf = walk.confidence.copy()
        conf[:, BODY15.index("mid_hip")] = 0
        walk = walk.replace(confidence=conf)
    with caplog.at_level(logging.WARNING, logger="clone.drive.stage"):
        out, fit = fit_to_stage(walk, ref)
    assert out is walk and fit == StageFit(share=0.0, reason=fit.reason) and not fit.moved
    assert fit.reason and fit.reason in caplog.text


def test_a_reference_standing_in_one_place_keeps_one_size():
    ref = figure(np.full(30, 250.0) + np.sin(np.arange(30)), np.full(30, 330.0), 100.0)
    walk = figure(np.full(30, 250.0), np.linspace(330, 430, 30), 100.0)
    out, fit = fit_to_stage(walk, ref)
    stage = reference_stage(ref)
    assert stage.slope == 0.0 and fit.moved
    height = out.joint("r_ankle")[:, 1] - out.joint("nose")[:, 1]
    np.testing.assert_allclose(height, walk.joint("r_ankle")[:, 1] - walk.joint("nose")[:, 1], atol=1e-3)
    assert np.abs(foot_y(out) - 330).max() <= stage.margin + 1e-3


def test_fit_interval():
    assert fit_interval(2, 5, 0, 10) == (1.0, 0.0)
    assert fit_interval(8, 12, 0, 10) == (1.0, -2.0)
    assert fit_interval(-3, 1, 0, 10) == (1.0, 3.0)
    scale, shift = fit_interval(-10, 30, 0, 10)
    assert scale == pytest.approx(0.25) and (scale * -10 + shift, scale * 30 + shift) == pytest.approx((0, 10))


def test_a_wider_margin_accepts_more():
    ref = reference()
    walk = figure(np.linspace(250, 320, 50), np.full(50, 330.0), 110.0)
    assert fit_to_stage(walk, ref)[1].moved
    assert not fit_to_stage(walk, ref, StageConfig(margin=0.5))[1].moved


def test_a_reference_that_looks_smaller_when_closer_gives_no_falling_size_line():
    # Crouching at the front of the stage: the apparent height follows the pose, not the camera.
    s = 0.5 - 0.5 * np.cos(np.linspace(0, 2 * np.pi, 60))
    ref = figure(200 + 100 * s, 300 + 60 * s, 120 - 40 * s)
    assert reference_stage(ref).slope == 0.0
    assert reference_stage(reference()).slope == pytest.approx(20 / 60, rel=0.1)  # EDN end-band estimates
    steep = figure(200 + 100 * s, 300 + 60 * s, 60 + 300 * s)
    assert reference_stage(steep).slope == StageConfig().max_slope


PICTURE = (0.0, 0.0, SIZE[0] - 1.0, SIZE[1] - 1.0)


def test_in_the_picture_a_walk_wider_than_the_stage_keeps_its_travel():
    ref = reference()
    walk = figure(np.linspace(100, 500, 60), np.linspace(330, 380, 60), 110.0)  # 4x the reference's range
    out, fit = fit_to_stage(walk, ref, picture=PICTURE)
    assert out is walk and not fit.moved and fit.share == 0.0
    assert fit_to_stage(walk, ref)[1].x_scale < 0.5  # on the reference's stage it is squeezed


def test_in_the_picture_a_track_leaving_it_is_shifted_back_whole_and_compressed_only_if_wider():
    ref = reference()
    margin = reference_stage(ref).margin
    walk = figure(np.linspace(300, 700, 60), np.full(60, 330.0), 110.0)  # walks off the right edge
    out, fit = fit_to_stage(walk, ref, picture=PICTURE)
    assert fit.moved and fit.x_scale == 1.0 and fit.x_shift < 0 and fit.share > 0.1
    np.testing.assert_allclose(out.joints - walk.joints, np.broadcast_to([fit.x_shift, 0.0], walk.joints.shape),
                               atol=1e-3)
    assert np.nanmax(out.joints[..., 0]) == pytest.approx(SIZE[0] - 1 - margin, abs=1e-3)
    wide = figure(np.linspace(-400, 1000, 60), np.full(60, 330.0), 110.0)  # wider than the picture
    out, fit = fit_to_stage(wide, ref, picture=PICTURE)
    assert 0 < fit.x_scale < 1
    x = out.joints[..., 0]
    assert np.nanmin(x) >= margin - 1e-3 and np.nanmax(x) <= SIZE[0] - 1 - margin + 1e-3
    np.testing.assert_allclose(np.diff(root_x(out), 2), 0.0, atol=1e-3)  # one map: the velocity stays constant
    # a jump above the top edge brings the whole track down by the same amount
    high = figure(np.full(30, 250.0), np.full(30, 100.0), 110.0)
    out, fit = fit_to_stage(high, ref, picture=PICTURE)
    assert fit.foot_shift > 0 and np.nanmin(out.joints[..., 1]) == pytest.approx(margin, abs=1.0)


def test_a_retargeted_track_starts_where_the_reference_stands():
    ref = reference()
    walk = figure(np.linspace(0, 400, 50), np.linspace(380, 400, 50), 110.0)
    out = start_on_reference(walk, ref)
    start = slice(0, round(0.5 * walk.fps))
    assert np.median(root_x(out)[start]) == pytest.approx(np.median(root_x(ref)), abs=1e-3)
    assert np.median(foot_y(out)[start]) == pytest.approx(np.median(foot_y(ref)), abs=1e-3)
    np.testing.assert_allclose(np.diff(out.joints, axis=0), np.diff(walk.joints, axis=0), atol=1e-3)  # same travel
    nobody = walk.replace(confidence=np.zeros_like(walk.confidence))
    assert start_on_reference(nobody, ref) is nobody


def test_in_the_picture_frames_without_anybody_are_carried_quietly(recwarn):
    walk = figure(np.linspace(300, 700, 30), np.full(30, 330.0), 110.0)
    joints = walk.joints.copy()
    joints[10] = np.nan  # nobody in this frame
    holes = walk.replace(joints=joints, confidence=np.where(np.isnan(joints[..., 0]), 0, 1).astype(np.float32))
    out, fit = fit_to_stage(holes, reference(), picture=PICTURE)
    assert fit.moved and np.isnan(out.joints[10]).all() and np.isfinite(out.joints[11]).all()
    assert not [w for w in recwarn if issubclass(w.category, RuntimeWarning)]
