"""clone.model.background: the plate of a static camera, recovered from frames where the person is elsewhere."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from clone.model.background import PlateConfig, estimate_plate, person_mask, sample_frames
from clone.model.canvas import Canvas
from clone.model.networks import GeneratorConfig, build_generator
from clone.model.reference import ReferenceModel
from clone.runtime.generate import generate_frames
from pose_io import BODY15, InputError, PoseTrack

H, W = 48, 96
# A standing body15 figure 30 px tall, feet at y = 0 (x, y per joint in BODY15 order).
FIGURE = 30.0 * np.array(
    [[0, -0.62], [0, -0.5], [-0.12, -0.48], [-0.16, -0.3], [-0.17, -0.12], [0.12, -0.48], [0.16, -0.3],
     [0.17, -0.12], [0, 0], [-0.07, 0], [-0.08, 0.2], [-0.08, 0.4], [0.07, 0], [0.08, 0.2], [0.08, 0.4]])


def _background() -> np.ndarray:
    return np.random.default_rng(0).integers(0, 256, (H, W, 3), dtype=np.uint8)


def _walk(frames: int, x_from: float, x_to: float) -> np.ndarray:
    """[T, 15, 2] the figure walking from ``x_from`` to ``x_to`` along y = 30."""
    xs = np.linspace(x_from, x_to, frames)
    joints = np.repeat(FIGURE[None], frames, axis=0) + np.array([0.0, 30.0])
    joints[..., 0] += xs[:, None]
    return joints.astype(np.float32)


def _film(joints: np.ndarray, background: np.ndarray, colour: int = 7) -> np.ndarray:
    """[T, H, W, 3]: a solid person, inside the region ``person_mask`` gives with margin 0.15, over the plate."""
    frames = np.repeat(background[None], len(joints), axis=0)
    for t, pose in enumerate(joints):
        inside = person_mask(pose, (H, W), BODY15, radius=0.08 * 30.0)
        frames[t][inside] = (colour, 200, 30 + t % 50)
    return frames


def test_a_moving_person_over_a_known_background_is_recovered_exactly():
    background = _background()
    # Standing in the middle for most of the video (a plain median would show the person there), then
    # walking off to the left, and later to the right.
    joints = np.concatenate([_walk(40, 48.0, 48.0), _walk(20, 48.0, -15.0), _walk(20, 48.0, W + 15.0)])
    frames = _film(joints, background)
    assert (np.median(frames, axis=0) != background).any()
    plate = estimate_plate(frames, joints, BODY15)
    assert plate.image.dtype == np.uint8 and plate.image.shape == (H, W, 3)
    np.testing.assert_array_equal(plate.image, background)
    assert plate.fallback_share == 0.0 and plate.frames == 80
    assert plate.free_frames.min() > 0 and plate.free_frames.max() == 80


def test_pixels_never_free_are_filled_from_around_them_not_painted_with_the_person():
    background = _background()
    joints = _walk(21, 40.0, 56.0)  # barely moves: its middle is covered in every frame
    frames = _film(joints, background)
    plate = estimate_plate(frames, joints, BODY15)
    covered = plate.free_frames == 0
    assert 0.0 < plate.fallback_share == pytest.approx(covered.mean())
    assert covered[30, 48] and not covered[5, 5]
    np.testing.assert_array_equal(plate.image[~covered], background[~covered])
    # The median of all frames there is the person's own colour (7, 200, .): a ghost. Inpainted from the noise
    # around it, the hole takes the background's colours instead.
    person = np.median(frames, axis=0)[covered].astype(float)
    assert np.abs(person[:, :2] - (7, 200)).max() < 1
    filled = plate.image[covered].astype(float)
    assert np.abs(filled[:, :2] - (7, 200)).mean() > 40
    assert abs(filled.mean() - background.mean()) < 40


def test_frames_without_a_pose_say_nothing_about_where_the_person_is_not():
    background = _background()
    joints = _walk(30, -10.0, W + 10.0)
    frames = _film(joints, background)
    # Most frames show the person standing still in the middle, with no detected pose: counted as free, they
    # would make the person the median there.
    still = _walk(1, 48.0, 48.0)[0]
    lost = _film(np.repeat(still[None], 40, axis=0), background)
    frames = np.concatenate([frames, lost])
    joints = np.concatenate([joints, np.full((40, 15, 2), np.nan, np.float32)])
    np.testing.assert_array_equal(estimate_plate(frames, joints, BODY15).image, background)
    # Poses the caller marks unusable are left out as well (here: wrong ones, far from the person).
    joints[30:] = _walk(1, 5.0, 5.0)[0]
    usable = np.arange(70) < 30
    np.testing.assert_array_equal(estimate_plate(frames, joints, BODY15, usable=usable).image, background)
    assert not np.array_equal(estimate_plate(frames, joints, BODY15).image, background)
    joints[30:] = np.nan
    with pytest.raises(InputError, match="no frame has a visible joint"):
        estimate_plate(frames[30:], joints[30:], BODY15)


def test_memory_is_bounded_by_the_frames_used():
    assert list(sample_frames(10, 4)) == [0, 3, 6, 9]
    assert list(sample_frames(3, 150)) == [0, 1, 2]
    background = _background()
    joints = _walk(400, -10.0, W + 10.0)
    plate = estimate_plate(_film(joints, background), joints, BODY15, config=PlateConfig(max_frames=25))
    assert plate.frames == 25
    np.testing.assert_array_equal(plate.image, background)


def test_person_mask_covers_the_skeleton_with_a_margin():
    pose = _walk(1, 48.0, 48.0)[0]
    mask = person_mask(pose, (H, W), BODY15, radius=3.0)
    for x, y in pose:
        assert mask[round(y), round(x)]
    assert mask[round(pose[1, 1]), round(pose[1, 0]) + 3] and not mask[round(pose[1, 1]), round(pose[1, 0]) + 12]
    assert mask[15:30].any() and not mask[:, :30].any()  # nowhere near the person
    missing = pose.copy()
    missing[:] = np.nan
    assert not person_mask(missing, (H, W), BODY15, 3.0).any()
    with pytest.raises(InputError, match="3 frames but 2 poses"):
        estimate_plate(np.zeros((3, H, W, 3), np.uint8), np.zeros((2, 15, 2), np.float32), BODY15)


def test_driving_a_model_with_a_plate_composites_over_it():
    # A generator whose alpha is zero everywhere draws nothing: every driven frame is exactly the stored plate.
    torch.manual_seed(0)
    config = GeneratorConfig(base_channels=4, depth=2, max_channels=8, alpha=True)
    net = build_generator("unet", config)
    with torch.no_grad():
        head = [m for m in net.head.modules() if isinstance(m, (torch.nn.Conv2d, torch.nn.ConvTranspose2d))][-1]
        head.weight[3:] = 0.0
        head.bias[3:] = -50.0
    plate = np.random.default_rng(2).integers(0, 256, (16, 16, 3), dtype=np.uint8)
    joints = _walk(3, 40.0, 50.0)
    track = PoseTrack(joints, np.ones(joints.shape[:2], np.float32), 25.0, (W, H), "body15")
    model = ReferenceModel("unet", config, net.state_dict(), Canvas(0, 0, W, 16, (W, H), "full"), None, track, {},
                           plate=plate)
    frames = [frame for _, frame in generate_frames(model, track)]
    assert len(frames) == 3
    for frame in frames:
        np.testing.assert_array_equal(frame, plate)
