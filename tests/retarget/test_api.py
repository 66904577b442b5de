import dataclasses

import numpy as np
import pytest
import torch

from pose_io import InputError, PoseTrack
from pose_io.clean import hold_fill, smooth_joints
from pose_io.measures import reference_limb_lengths, skeleton_height
from pose_io.readers import read_track
from pose_io.resample import resample
from retarget import api
from retarget.api import InferenceConfig, ReferenceCodes, load_retargeter
from retarget.inference.placement import placement_of
from retarget.inference.tracks import to_body15


@pytest.fixture(scope="module")
def weights_dir(shared_dir):
    return shared_dir / "official_2dmr" / "weights"


@pytest.fixture(scope="module")
def retargeter(weights_dir):
    torch.set_num_threads(1)
    return load_retargeter(weights_dir / "pretrained_full.pth", config=InferenceConfig(refine_steps=0))  # as released


@pytest.fixture(scope="module")
def clips(shared_dir):
    return {c: read_track(shared_dir / "openpose_examples" / c, image_size=(720, 720)) for c in ("tall_man", "small_man")}


def _clean(track: PoseTrack) -> np.ndarray:
    """The track as the network sees it, in its own pixels: filled and smoothed body15."""
    return smooth_joints(hold_fill(to_body15(track).joints.astype(np.float64)), 2.0)


def _tiled(track: PoseTrack, frames: int) -> PoseTrack:
    reps = frames // len(track) + 1
    # Play forwards then backwards so the tiled track has no jumps.
    joints = np.concatenate([track.joints, track.joints[::-1]] * reps)[:frames]
    conf = np.concatenate([track.confidence, track.confidence[::-1]] * reps)[:frames]
    return track.replace(joints=joints, confidence=conf)


@pytest.mark.parametrize("frames", [16, 17, 23, 64, 121])
def test_any_length_gives_as_many_frames(retargeter, clips, frames):
    reference = retargeter.reference_codes(clips["tall_man"])
    out = retargeter.retarget(clips["small_man"].frames(0, frames), reference)
    assert len(out) == frames and out.layout == "body15"
    assert out.image_size == clips["tall_man"].image_size and out.fps == clips["small_man"].fps
    assert not out.missing.any()


def test_long_tracks_in_windows_match_one_pass(retargeter, clips):
    track = _tiled(clips["small_man"], 700)
    reference = retargeter.reference_codes(clips["tall_man"])
    windowed = dataclasses.replace(retargeter, config=InferenceConfig(window=128, overlap=32, refine_steps=0))
    one_pass = dataclasses.replace(retargeter, config=InferenceConfig(window=1024, refine_steps=0))
    a = windowed.retarget(track, reference).joints
    b = one_pass.retarget(track, reference).joints
    assert len(a) == 700
    rel = lambda j: j - j[:, 8:9]
    height = skeleton_height(b)
    assert np.abs(rel(a) - rel(b)).mean() < 0.002 * height
    assert np.abs(np.diff(a, axis=0)).max() < 1.2 * np.abs(np.diff(b, axis=0)).max()  # no jumps where windows meet


def test_retargeting_onto_its_own_skeleton_and_view_reproduces_the_clip(retargeter, clips):
    for track in clips.values():
        out = retargeter.retarget(track, retargeter.reference_codes(track)).joints
        truth = _clean(track)
        height = skeleton_height(truth)
        pose_error = np.linalg.norm((out - out[:, 8:9]) - (truth - truth[:, 8:9]), axis=-1).mean()
        place_error = np.linalg.norm(out - truth, axis=-1).mean()
        # The authors' own reconstruction of these clips is off by 2.3 % (tall) and 2.4 % (small) of the height.
        assert pose_error < 0.03 * height
        assert place_error < 0.05 * height


def test_tall_motion_on_small_skeleton_takes_the_small_limbs(retargeter, clips):
    tall, small = clips["tall_man"], clips["small_man"]
    out = retargeter.retarget(tall, retargeter.reference_codes(small))
    lengths = reference_limb_lengths(out.joints)
    to_small = np.abs(lengths - reference_limb_lengths(_clean(small))).mean()
    to_tall = np.abs(lengths - reference_limb_lengths(_clean(tall))).mean()
    assert to_small < 0.25 * to_tall
    assert skeleton_height(out.joints) == pytest.approx(skeleton_height(_clean(small)), rel=0.15)


def test_output_stands_where_the_reference_stands(retargeter, clips):
    reference = retargeter.reference_codes(clips["small_man"])
    out = retargeter.retarget(clips["tall_man"], reference)
    placed = placement_of(out.joints)
    assert placed.root_x == pytest.approx(reference.placement.root_x, abs=1e-3)
    assert placed.ground_y == pytest.approx(reference.placement.ground_y, abs=1e-3)


def test_reference_codes_round_trip_through_a_checkpoint(retargeter, clips, tmp_path):
    codes = retargeter.reference_codes(clips["small_man"], view=clips["tall_man"])
    data = codes.to_dict()
    assert all(isinstance(v, np.ndarray) for v in data.values())
    torch.save({k: torch.from_numpy(v) for k, v in data.items()}, tmp_path / "ref.pt")
    back = ReferenceCodes.from_dict(torch.load(tmp_path / "ref.pt", weights_only=True))
    np.testing.assert_array_equal(back.body, codes.body)
    np.testing.assert_array_equal(back.view, codes.view)
    assert back.placement == codes.placement and back.image_size == codes.image_size
    assert retargeter.retarget(clips["tall_man"], back).equals(retargeter.retarget(clips["tall_man"], codes))
    with pytest.raises(InputError, match="malformed"):
        ReferenceCodes.from_dict({"body": codes.body})


def test_view_code_comes_from_the_view_track(retargeter, clips):
    own = retargeter.reference_codes(clips["small_man"])
    other = retargeter.reference_codes(clips["small_man"], view=clips["tall_man"])
    np.testing.assert_array_equal(own.body, other.body)
    np.testing.assert_array_equal(other.view, retargeter.reference_codes(clips["tall_man"]).view)


@pytest.mark.parametrize("windows", [1, 2, 3, 7])
def test_the_view_code_is_the_window_code_nearest_their_mean_and_the_skeleton_code_their_mean(retargeter, windows):
    """A person who turns is seen from several views: the mean of their view codes is no view's code."""
    rng = np.random.default_rng(windows)
    per_window = {"body": rng.normal(size=(windows, 16)), "view": rng.normal(size=(windows, 8))}
    seen = []

    def encode(batch, which):  # window k starts at frame 32 k and holds k in every value
        seen.append(len(batch))
        return per_window[which][batch[:, 0, 0].astype(int)].astype(np.float32)

    config = retargeter.config
    length = config.code_window + (windows - 1) * config.code_stride
    x = np.repeat(np.arange(length) // config.code_stride, 1)[None].repeat(30, axis=0).astype(np.float32)
    x = np.minimum(x, windows - 1)  # window k's first frame is k
    nearest = dataclasses.replace(retargeter, config=dataclasses.replace(config, view_pool="nearest"))
    mean = dataclasses.replace(retargeter, config=dataclasses.replace(config, view_pool="mean"))
    for net in (nearest, mean):
        object.__setattr__(net, "_encode_static", encode)
    codes = per_window["view"]
    expected_view = codes.mean(axis=0)
    if windows >= 3:  # with two windows both are equally near their mean: the mean it is
        expected_view = codes[np.argmin(((codes - codes.mean(axis=0)) ** 2).sum(axis=1))]
    np.testing.assert_allclose(nearest._static_code(x, "view"), expected_view, rtol=1e-6)
    np.testing.assert_allclose(mean._static_code(x, "view"), codes.mean(axis=0), rtol=1e-6)
    for net in (nearest, mean):
        np.testing.assert_allclose(net._static_code(x, "body"), per_window["body"].mean(axis=0), rtol=1e-6)
    with pytest.raises(ValueError, match="view_pool"):
        InferenceConfig(view_pool="median")


def test_bad_inputs(retargeter, clips, weights_dir):
    small = clips["small_man"]
    reference = retargeter.reference_codes(small)
    with pytest.raises(InputError, match="driver.json: 15 frames; the retargeting network needs at least 16"):
        retargeter.retarget(small.frames(0, 15), reference, name="driver.json")
    nobody = small.replace(confidence=np.zeros_like(small.confidence))
    with pytest.raises(InputError, match="no joints detected"):
        retargeter.retarget(nobody, reference)
    with pytest.raises(InputError, match="no joints detected"):
        retargeter.reference_codes(nobody)
    skeleton_model = load_retargeter(weights_dir / "pretrained_skeleton.pth")
    with pytest.raises(InputError, match="different retargeting model"):
        retargeter.retarget(small, skeleton_model.reference_codes(small))
    with pytest.raises(InputError, match="unknown device"):
        load_retargeter(weights_dir / "pretrained_full.pth", device="tpu")


def test_other_layouts_are_converted(retargeter, clips):
    small = clips["small_man"]
    coco = small.to_layout("coco18")
    out = retargeter.retarget(coco, retargeter.reference_codes(small))
    assert len(out) == len(small)


def test_missing_packaged_weights_say_what_to_do(monkeypatch, tmp_path):
    monkeypatch.setattr(api, "PACKAGED_WEIGHTS", tmp_path / "clone2d_full.pt")
    with pytest.raises(InputError, match="no trained retargeting weights are shipped yet.*--weights"):
        load_retargeter()


def test_body_normalised_results_do_not_depend_on_the_guessed_image_size(weights_dir, shared_dir):
    """OpenPose JSON stores no image size; with body-height normalisation the guess must not matter."""
    from retarget.network.checkpoint import load_weights

    loaded = load_weights(weights_dir / "pretrained_full.pth")
    body = api.Retargeter(loaded.model, loaded.stats, dataclasses.replace(loaded.preprocess, body_height=160.0),
                          torch.device("cpu"))  # fmt: skip
    image = api.Retargeter(loaded.model, loaded.stats, loaded.preprocess, torch.device("cpu"))
    outputs = {}
    for size in [(720, 720), (1920, 1080), None]:
        motion = read_track(shared_dir / "openpose_examples" / "tall_man", image_size=size)
        reference = read_track(shared_dir / "openpose_examples" / "small_man", image_size=size)
        outputs[size] = (body.retarget(motion, body.reference_codes(reference)).joints,
                         image.retarget(motion, image.reference_codes(reference)).joints)  # fmt: skip
    first = outputs[(720, 720)]
    for size, (by_body, by_image) in outputs.items():
        np.testing.assert_allclose(by_body, first[0], atol=1e-3)
        if size != (720, 720):  # the authors' rule changes with the guess
            assert np.abs(by_image - first[1]).max() > 1.0


def test_reference_codes_keep_their_scale_and_refuse_a_bad_one(retargeter, clips):
    codes = retargeter.reference_codes(clips["small_man"])
    assert codes.scale == pytest.approx(512 / 720)
    back = ReferenceCodes.from_dict(codes.to_dict())
    assert back.scale == codes.scale
    with pytest.raises(InputError, match="scale"):
        ReferenceCodes.from_dict({**codes.to_dict(), "scale": np.array(-1.0)})


def test_other_frame_rates_run_at_the_networks_and_come_back_to_their_own(retargeter, clips):
    small, tall = clips["small_man"], clips["tall_man"]  # 30 fps
    reference = retargeter.reference_codes(tall)
    at_30 = retargeter.retarget(small, reference)
    fast = resample(small, 60.0)  # every other frame is one of the 30 fps track's
    at_60 = retargeter.retarget(fast, reference)
    assert (len(at_60), at_60.fps) == (len(fast), 60.0) and not at_60.missing.any()
    np.testing.assert_array_equal(at_60.joints[::2], at_30.joints)  # 60 -> 30 takes every other frame exactly
    fast_reference = retargeter.reference_codes(resample(tall, 60.0))
    np.testing.assert_array_equal(fast_reference.body, reference.body)
    np.testing.assert_array_equal(fast_reference.view, reference.view)
    # Within 1 % of the rate (29.97 fps video): as it is.
    ntsc = retargeter.retarget(small.replace(fps=29.97), reference)
    assert ntsc.fps == 29.97
    np.testing.assert_array_equal(ntsc.joints, at_30.joints)
    # fps 0: every track at its own rate; a 60 fps driver then looks slowed down to the network.
    own_rate = dataclasses.replace(retargeter, config=InferenceConfig(refine_steps=0, fps=0.0))
    slowed = own_rate.retarget(fast, reference)
    assert len(slowed) == len(fast) and not np.allclose(slowed.joints[::2], at_30.joints, atol=1.0)


def test_a_high_rate_track_too_short_at_the_networks_rate_is_refused(retargeter, clips):
    short = clips["small_man"].frames(0, 20).replace(fps=60.0)
    reference = retargeter.reference_codes(clips["tall_man"])
    with pytest.raises(InputError, match="d.json: 20 frames at 60 fps, 10 at the network's 30 fps; .* at least 16"):
        retargeter.retarget(short, reference, name="d.json")
    with pytest.raises(InputError, match="r.json: 20 frames at 60 fps"):
        retargeter.reference_codes(short, name="r.json")
    crawl = _tiled(clips["small_man"], 400).replace(fps=0.01)  # 1,197,001 frames at 30 fps
    with pytest.raises(InputError, match="c.json: 400 frames at 0.01 fps, at the network's 30 fps: 1,197,001 frames;"
                                         " at most 1,000,000"):
        retargeter.retarget(crawl, reference, name="c.json")
    for bad in (-1.0, float("nan"), float("inf"), 1e-5, 5000.0):
        with pytest.raises(ValueError, match="fps must be 0 or from 0.01 to 1000"):
            InferenceConfig(fps=bad)


def _facing_windows(signs: list[int], stats) -> np.ndarray:
    """[N, 30, 64] network input of a standing body facing the camera (+1), showing its back (-1) or its side (0)."""
    from retarget.network.preprocess import LOCAL_JOINTS, NUM_ROWS

    rows = np.zeros((len(signs), NUM_ROWS, 2, 64))
    for k, sign in enumerate(signs):
        rows[k, LOCAL_JOINTS.index("neck"), 1] = -50.0  # the neck 50 px above the MidHip
        rows[k, LOCAL_JOINTS.index("r_shoulder"), 0] = -15.0 * sign  # facing: the right shoulder on the left
        rows[k, LOCAL_JOINTS.index("l_shoulder"), 0] = 15.0 * sign
    return ((rows - stats.mean[None, :, :, None]) / stats.std[None, :, :, None]).reshape(len(signs), 30, 64)


def test_a_reference_who_shows_her_back_gets_the_view_she_shows_most(retargeter):
    from retarget.inference.algorithm import pool_view_codes, window_facing

    signs = [1, 1, 1, 0, -1, -1, 1, 1]
    assert window_facing(_facing_windows(signs, retargeter.stats), retargeter.stats).tolist() == signs
    rng = np.random.default_rng(0)
    front, back = rng.normal(size=8), rng.normal(size=8) + 3.0
    codes = np.stack([front + 0.1 * rng.normal(size=8) if s > 0 else back if s < 0 else (front + back) / 2
                      for s in signs])
    facing = np.array(signs)
    chosen = pool_view_codes(codes, "facing", facing)
    fronts = codes[facing == 1]
    np.testing.assert_allclose(chosen, fronts[np.argmin(((fronts - fronts.mean(0)) ** 2).sum(1))], rtol=1e-6)
    # never turning: the window nearest the mean of all, as "nearest"
    same = np.ones(len(signs), dtype=int)
    np.testing.assert_array_equal(pool_view_codes(codes, "facing", same), pool_view_codes(codes, "nearest"))
    assert InferenceConfig().view_pool == "facing"
