import dataclasses

import pytest

from clone.cartoon.character import PRESETS
from clone.cartoon.reference import character_lengths, estimate_yaw, framing_of, reference_track
from pose_io.measures import skeleton_height
from retarget.inference.placement import placement_of
from retarget.inference.tracks import to_body15
from retarget.network.preprocess import LAYOUT


def test_reference_track_stands_where_the_driver_stands_at_its_scale(driver):
    framing = framing_of(driver)
    track = reference_track(PRESETS["standard"], framing, driver.fps)
    assert track.layout == "body15" and track.image_size == driver.image_size and track.fps == driver.fps
    assert not track.missing.any()
    mine, theirs = placement_of(track.joints), placement_of(to_body15(driver).joints)
    assert mine.root_x == pytest.approx(theirs.root_x, abs=1.0)
    assert mine.ground_y == pytest.approx(theirs.ground_y, abs=1.0)
    assert mine.height == pytest.approx(theirs.height, rel=1e-6)  # a standard body measures as tall as the driver


def test_the_motion_is_resampled_to_the_driver_rate(driver):
    framing = framing_of(driver)
    assert len(reference_track(PRESETS["chibi"], framing, 15.0, frames=61)) == 31


def test_proportions_follow_the_spec(driver):
    framing = framing_of(driver)
    neck_nose = LAYOUT.limbs.index(("neck", "nose"))
    shin = LAYOUT.limbs.index(("l_knee", "l_ankle"))
    standard, _ = character_lengths(reference_track(PRESETS["standard"], framing, driver.fps))
    big, _ = character_lengths(reference_track(PRESETS["bighead"], framing, driver.fps))
    stubby_track = reference_track(PRESETS["stubby"], framing, driver.fps)
    stubby, height = character_lengths(stubby_track)
    assert big[neck_nose] == pytest.approx(2 * standard[neck_nose], rel=1e-3)
    assert stubby[shin] == pytest.approx(0.55 * standard[shin], rel=1e-3)
    assert height == pytest.approx(skeleton_height(stubby_track.joints))


@pytest.mark.parametrize("yaw", [-60.0, -30.0, 0.0, 45.0])
def test_the_yaw_of_a_standard_body_is_recovered(driver, yaw):
    framing = dataclasses.replace(framing_of(driver), yaw=yaw)
    seen = reference_track(PRESETS["standard"], framing, driver.fps)
    assert estimate_yaw(seen) == pytest.approx(yaw, abs=5.0)
