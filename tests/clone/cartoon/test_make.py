import numpy as np
import pytest

from clone.cartoon import PRESETS, make_cartoon, summary_lines
from clone.cartoon.proportions import held_limbs
from pose_io import InputError
from pose_io.measures import limb_lengths


@pytest.mark.parametrize("preset, yaw", [("stubby", None), ("bighead", 30.0)])
def test_proportions_are_held_in_every_frame(driver, retargeter, preset, yaw):
    cartoon = make_cartoon(driver, PRESETS[preset], retargeter, yaw=yaw)
    assert len(cartoon.track) == len(driver) and cartoon.track.layout == "body15"
    assert cartoon.track.image_size == driver.image_size and not cartoon.track.missing.any()
    lengths = limb_lengths(cartoon.track.joints)[:, held_limbs()]  # [T, 10]
    np.testing.assert_allclose(lengths, np.broadcast_to(cartoon.lengths[held_limbs()], lengths.shape), rtol=1e-4)
    errors = cartoon.report["limb_error_pct"]
    assert errors["after_fix"]["mean_pct"] < 1e-3
    assert errors["network"]["mean_pct"] > 0 and errors["global_scale"]["mean_pct"] > 0
    assert cartoon.report["fix_moved_pct"]["max_pct"] >= cartoon.report["fix_moved_pct"]["mean_pct"] > 0
    assert cartoon.report["view"].startswith("driver's") if yaw is None else cartoon.report["view"] == "yaw 30"
    assert errors["reference"]["mean_pct"] < errors["network"]["mean_pct"]
    assert len(summary_lines(cartoon.report)) == 3


def test_the_network_output_is_the_cartoon_before_the_fix(driver, retargeter):
    cartoon = make_cartoon(driver, PRESETS["longarms"], retargeter)
    moved = np.linalg.norm(cartoon.track.joints - cartoon.network.joints, axis=-1)
    root = cartoon.track.joint_layout.index("mid_hip")
    assert np.all(moved[:, root] == 0)
    assert moved.mean() / cartoon.report["height_px"] * 100 == pytest.approx(
        cartoon.report["fix_moved_pct"]["mean_pct"], rel=1e-3)


def test_a_too_short_driver_is_an_input_error(driver, retargeter):
    with pytest.raises(InputError, match="at least"):
        make_cartoon(driver.frames(0, 10), PRESETS["chibi"], retargeter)
