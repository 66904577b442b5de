"""The numpy backend retargets as the torch one does, one track or many at once (packaged weights)."""

from __future__ import annotations

import dataclasses
import sys

import numpy as np
import pytest

from pose_io.errors import InputError
from pose_io.resample import resample
from retarget.api import InferenceConfig, NumpyRetargeter, Retargeter, load_retargeter
from tests.figures import tall_and_small, walking_figure

PX = 2e-3  # pixels; measured ~1e-4 (float32 rounding of 500-pixel coordinates)


pytestmark = pytest.mark.usefixtures("one_thread")


@pytest.fixture(scope="module")
def backends() -> tuple[Retargeter, NumpyRetargeter]:
    # long tracks cross several windows (without refinement: its parity is tested below)
    small = InferenceConfig(window=128, overlap=32, batch=2, refine_steps=0)
    return load_retargeter(config=small), load_retargeter(config=small, backend="numpy")


@pytest.fixture(scope="module")
def people():
    return tall_and_small(96)


def test_reference_codes_agree(backends, people):
    codes = [b.reference_codes(people["tall"], people["small"]) for b in backends]
    np.testing.assert_allclose(codes[0].body, codes[1].body, atol=1e-5)
    np.testing.assert_allclose(codes[0].view, codes[1].view, atol=1e-5)
    assert codes[0].placement == codes[1].placement and codes[0].scale == codes[1].scale


@pytest.mark.parametrize("frames", [16, 45, 96, 300])
def test_retargeted_poses_agree(backends, people, frames):
    reference = backends[0].reference_codes(people["small"])
    driver = walking_figure(frames, seed=frames)
    a, b = (r.retarget(driver, reference) for r in backends)
    assert a.equals(b, atol=PX)


def test_many_clips_at_once_equal_one_at_a_time(backends, people):
    numpy_backend = backends[1]
    reference = numpy_backend.reference_codes(people["small"])
    drivers = [walking_figure(n, seed=n) for n in (40, 96, 96, 300, 17)]
    many = numpy_backend.retarget_many(drivers, reference)
    assert [len(m) for m in many] == [len(d) for d in drivers]
    for driver, moved in zip(drivers, many):
        assert moved.equals(numpy_backend.retarget(driver, reference), atol=PX)
    torch_many = backends[0].retarget_many(drivers, reference)
    assert all(a.equals(b, atol=PX) for a, b in zip(many, torch_many))


def test_a_bad_clip_among_many_is_named_before_any_work(backends, people):
    numpy_backend = backends[1]
    reference = numpy_backend.reference_codes(people["small"])
    too_short = walking_figure(4, seed=0)
    with pytest.raises(InputError, match="clip 2: 4 frames"):
        numpy_backend.retarget_many([walking_figure(40), walking_figure(50), too_short], reference,
                                    names=["clip 0", "clip 1", "clip 2"])  # fmt: skip


def test_codes_of_another_network_are_refused(backends, people):
    reference = backends[1].reference_codes(people["small"])
    wrong = dataclasses.replace(reference, body=np.zeros(3, np.float32))
    with pytest.raises(InputError, match="skeleton code of size 3"):
        backends[1].retarget(people["tall"], wrong)


def test_numpy_backend_modules_import_without_torch():
    import subprocess

    code = ("import sys; import retarget.api, retarget.inference.batch, retarget.network.numpy_weights, retarget.inference.config, "
            "retarget.runtime, retarget.network.blas, pose_io, pose_io.readers, pose_io.writers; "
            "config = retarget.inference.config.InferenceConfig(refine_steps=0); "
            "retarget.api.load_retargeter(config=config, backend='auto'); print('torch' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False", out.stderr


def test_auto_takes_numpy_for_the_default_refined_codes_and_both_backends_agree(people):
    assert InferenceConfig().refine_steps > 0
    numpy_backend = load_retargeter(backend="auto")  # the default: refined codes, no torch
    assert isinstance(numpy_backend, NumpyRetargeter) and numpy_backend.config == InferenceConfig()
    torch_backend = load_retargeter(backend="torch")
    # several windows of a long track, a short clip, and a track at another frame rate
    long = walking_figure(400, seed=3)
    tracks = [long, people["tall"], walking_figure(90, seed=4, fps=25.0)]
    small = InferenceConfig(window=128, overlap=32)
    for config in (InferenceConfig(), small):
        ours, theirs = (dataclasses.replace(b, config=config) for b in (numpy_backend, torch_backend))
        reference = theirs.reference_codes(people["small"])
        for track in tracks:
            a, b = ours.retarget(track, reference), theirs.retarget(track, reference)
            assert a.equals(b, atol=PX), np.abs(a.joints - b.joints).max()
        plain = dataclasses.replace(theirs, config=dataclasses.replace(config, refine_steps=0))
        assert np.abs(plain.retarget(long, reference).joints - theirs.retarget(long, reference).joints).max() > 0.5


def test_clips_at_several_rates_at_once_keep_each_its_frames_and_rate(backends, people):
    numpy_backend, torch_backend = backends[1], backends[0]
    reference = numpy_backend.reference_codes(people["small"])
    base = walking_figure(96, seed=7)
    drivers = [resample(base, fps) for fps in (60.0, 24.0, 29.9, 15.0)]  # 15 fps: 48 frames, 95 at 30 fps
    many = numpy_backend.retarget_many(drivers, reference)
    assert [(len(m), m.fps) for m in many] == [(len(d), d.fps) for d in drivers]
    for driver, moved in zip(drivers, many):
        assert moved.equals(numpy_backend.retarget(driver, reference), atol=PX)
    assert all(a.equals(b, atol=PX) for a, b in zip(many, torch_backend.retarget_many(drivers, reference)))
    short = resample(walking_figure(12, seed=3), 15.0)  # 6 frames at 15 fps, 11 at 30: too few either way
    with pytest.raises(InputError, match="6 frames at 15 fps, 11 at the network's 30 fps"):
        numpy_backend.retarget(short, reference)
    upsampled = resample(walking_figure(20, seed=3), 15.0)  # 10 frames at 15 fps, 19 at 30: enough
    assert len(numpy_backend.retarget(upsampled, reference)) == 10


def test_a_view_track_at_another_rate_gives_the_same_view_code(backends, people):
    r = backends[1]
    at_30 = r.reference_codes(people["tall"], people["small"])
    at_60 = r.reference_codes(people["tall"], resample(people["small"], 60.0))
    np.testing.assert_allclose(at_60.view, at_30.view, atol=1e-3)  # the body's scale: medians over its own frames
    with pytest.raises(InputError, match="v.npz: 20 frames at 60 fps, 10 at the network's 30 fps"):
        r.reference_codes(people["tall"], people["small"].frames(0, 20).replace(fps=60.0), view_name="v.npz")
