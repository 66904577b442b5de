"""retarget.api with the weights shipped in the package, on tracks the tests build (no ../shared needed).

The shipped weights get replaced by better ones from time to time, so nothing here holds numbers of one
set of weights: only what any usable retargeting network must do (frame counts, shapes, placement, the
reference's proportions kept better than global scaling keeps them, codes that round-trip, clear errors).
The parity of the network itself with the authors' release is in test_model.py (on ../shared).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import torch

from pose_io import InputError
from pose_io.clean import smooth_joints
from pose_io.compare import pose_error
from pose_io.measures import proportion_error, skeleton_height
from retarget import api
from retarget.api import InferenceConfig, ReferenceCodes, load_retargeter
from retarget.baselines.methods import global_scale_retarget
from retarget.inference.placement import placement_of
from retarget.inference.tracks import filled_body15
from retarget.network.checkpoint import KIND, load_weights
from retarget.network.model import VARIANTS
from retarget.network.preprocess import LAYOUT, ROOT_INDEX
from tests.figures import tall_and_small, walking_figure


@pytest.fixture(scope="module")
def retargeter() -> api.Retargeter:
    return load_retargeter()  # None = the packaged weights


@pytest.fixture(scope="module")
def people():
    return tall_and_small(128)


def _proportion_error(joints: np.ndarray, reference) -> float:
    """How far ``joints`` are from the reference's proportions (% of its height)."""
    return proportion_error(joints, filled_body15(reference, "reference"), LAYOUT)


def _root_relative(joints: np.ndarray) -> np.ndarray:
    return joints - joints[:, ROOT_INDEX : ROOT_INDEX + 1]  # [T, 15, 2]


def test_packaged_weights_are_a_clone2d_checkpoint():
    assert api.PACKAGED_WEIGHTS.is_file()
    raw = torch.load(api.PACKAGED_WEIGHTS, map_location="cpu", weights_only=True)
    assert raw["kind"] == KIND and raw["layout"] == LAYOUT.name
    loaded = load_weights(api.PACKAGED_WEIGHTS)
    assert loaded.variant in VARIANTS
    assert loaded.stats.mean.shape == loaded.stats.std.shape


def test_packaged_weights_smooth_as_chosen_on_validation():
    from retarget.training.config import OUR_PREPROCESS

    shipped = load_weights(api.PACKAGED_WEIGHTS).preprocess
    assert (shipped.input_sigma, shipped.output_sigma) == (OUR_PREPROCESS.input_sigma, OUR_PREPROCESS.output_sigma)
    assert shipped.body_height > 0  # every track brought to one skeleton height


def test_packaged_weights_load_without_arguments(retargeter):
    assert retargeter.device == torch.device("cpu")
    assert not retargeter.model.training
    assert retargeter.variant in VARIANTS and retargeter.min_frames >= 1


@pytest.mark.parametrize("extra", [0, 1, 7, 48, 105])
def test_any_length_gives_as_many_frames(retargeter, people, extra):
    frames = retargeter.min_frames + extra
    reference = retargeter.reference_codes(people["tall"])
    driver = people["small"].replace(fps=25.0).frames(0, frames)
    out = retargeter.retarget(driver, reference)
    assert len(out) == frames and out.layout == "body15" and out.joints.shape == (frames, 15, 2)
    assert out.image_size == people["tall"].image_size and out.fps == 25.0
    assert not out.missing.any() and np.isfinite(out.joints).all()


def test_long_tracks_go_through_in_windows(retargeter, people):
    driver = walking_figure(300, seed=3)
    windowed = dataclasses.replace(retargeter, config=InferenceConfig(window=64, overlap=16, batch=2))
    out = windowed.retarget(driver, windowed.reference_codes(people["small"]))
    assert len(out) == 300 and np.isfinite(out.joints).all()


def test_output_stands_where_the_reference_stands(retargeter, people):
    reference = retargeter.reference_codes(people["small"])
    out = retargeter.retarget(people["tall"], reference)
    placed = placement_of(out.joints)
    assert placed.root_x == pytest.approx(reference.placement.root_x, abs=1e-3)
    assert placed.ground_y == pytest.approx(reference.placement.ground_y, abs=1e-3)


@pytest.mark.parametrize(("driver", "target"), [("tall", "small"), ("small", "tall")])
def test_the_reference_skeleton_is_kept_better_than_by_global_scaling(retargeter, people, driver, target):
    motion, reference = people[driver], people[target]
    out = retargeter.retarget(motion, retargeter.reference_codes(reference))
    scaled = global_scale_retarget(motion, reference)
    assert _proportion_error(out.joints, reference) < _proportion_error(scaled.joints, reference)
    # The output takes the reference's size, not the driver's.
    h_ref = skeleton_height(filled_body15(reference), LAYOUT)
    h_drv = skeleton_height(filled_body15(motion), LAYOUT)
    assert abs(skeleton_height(out.joints, LAYOUT) - h_ref) < abs(h_drv - h_ref) / 2


@pytest.mark.parametrize("who", ["tall", "small"])
def test_retargeting_onto_its_own_skeleton_and_view_keeps_the_poses(retargeter, people, who):
    track = people[who]
    out = retargeter.retarget(track, retargeter.reference_codes(track)).joints
    truth = smooth_joints(filled_body15(track), 2.0)
    height = skeleton_height(truth, LAYOUT)
    own = pose_error(_root_relative(out), _root_relative(truth), height)["rmse_pct"]
    # Closer to the clip than the other person's poses, brought to this one's size, are (0.62 of their error for
    # the small synthetic walker with the shipped weights, 1.0 or more for an untrained network).
    other = global_scale_retarget(people["small" if who == "tall" else "tall"], track).joints
    assert own < 0.75 * pose_error(_root_relative(other), _root_relative(truth), height)["rmse_pct"]
    assert own < 10.0  # % of the height: any usable network reconstructs within that


def test_results_are_deterministic(retargeter, people):
    reference = retargeter.reference_codes(people["small"])
    assert retargeter.retarget(people["tall"], reference).equals(retargeter.retarget(people["tall"], reference))


def test_reference_codes_round_trip_through_a_file(retargeter, people, tmp_path):
    codes = retargeter.reference_codes(people["small"], view=people["tall"])
    data = codes.to_dict()
    assert all(isinstance(v, np.ndarray) for v in data.values())
    torch.save({k: torch.from_numpy(v) for k, v in data.items()}, tmp_path / "ref.pt")
    back = ReferenceCodes.from_dict(torch.load(tmp_path / "ref.pt", weights_only=True))
    for name in ("body", "view"):
        if getattr(codes, name) is None:
            assert getattr(back, name) is None
        else:
            np.testing.assert_array_equal(getattr(back, name), getattr(codes, name))
    assert back.placement == codes.placement and back.image_size == codes.image_size and back.scale == codes.scale
    assert retargeter.retarget(people["tall"], back).equals(retargeter.retarget(people["tall"], codes))


def test_view_code_comes_from_the_view_track(retargeter, people):
    if retargeter.model.view_encoder is None:
        pytest.skip("the packaged network has no view encoder")
    own = retargeter.reference_codes(people["small"])
    other = retargeter.reference_codes(people["small"], view=people["tall"])
    if own.body is not None:
        np.testing.assert_array_equal(own.body, other.body)
    np.testing.assert_array_equal(other.view, retargeter.reference_codes(people["tall"]).view)


def test_other_layouts_are_converted(retargeter, people):
    reference = retargeter.reference_codes(people["small"])
    coco = people["tall"].to_layout("coco18")  # no mid_hip: body15's is the mean of the hips
    out = retargeter.retarget(coco, reference)
    assert len(out) == len(coco) and out.layout == "body15"
    assert out.equals(retargeter.retarget(coco.to_layout("body15"), reference))


def test_body_normalised_results_do_not_depend_on_the_image_size(people):
    """OpenPose JSON stores no image size; with body-height normalisation a wrong guess must not matter."""
    loaded = load_weights(api.PACKAGED_WEIGHTS)
    config = dataclasses.replace(loaded.preprocess, body_height=160.0)
    net = api.Retargeter(loaded.model, loaded.stats, config, torch.device("cpu"))
    outputs = []
    for size in [(720, 720), (1920, 1080), (640, 800)]:
        motion, reference = (people[k].replace(image_size=size) for k in ("tall", "small"))
        outputs.append(net.retarget(motion, net.reference_codes(reference)).joints)
    for joints in outputs[1:]:
        np.testing.assert_allclose(joints, outputs[0], atol=1e-3)


def test_bad_inputs(retargeter, people):
    small = people["small"]
    reference = retargeter.reference_codes(small)
    short = retargeter.min_frames - 1
    with pytest.raises(InputError, match=f"driver.json: {short} frames; the retargeting network needs at least "
                                         f"{retargeter.min_frames}"):
        retargeter.retarget(small.frames(0, short), reference, name="driver.json")
    nobody = small.replace(joints=np.full_like(small.joints, np.nan), confidence=np.zeros_like(small.confidence))
    with pytest.raises(InputError, match="no joints detected"):
        retargeter.retarget(nobody, reference)
    with pytest.raises(InputError, match="no joints detected"):
        retargeter.reference_codes(nobody)
    foreign = dataclasses.replace(reference, body=np.zeros(3, np.float32), view=np.zeros(2, np.float32))
    with pytest.raises(InputError, match="different retargeting model"):
        retargeter.retarget(small, foreign)
    with pytest.raises(InputError, match="unknown device"):
        load_retargeter(device="tpu")
