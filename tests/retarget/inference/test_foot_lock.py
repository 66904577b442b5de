"""retarget.inference.foot_lock and `clone retarget apply --foot-lock/--no-foot-lock` (shipped weights, numpy where exported)."""

import numpy as np
import pytest
from typer.testing import CliRunner

from clone.cli.main import app
from pose_io.feet import lock_feet
from pose_io.readers import read_track
from pose_io.resample import resample
from pose_io.writers import write_track
from retarget import api
from retarget.inference.batch import retarget_files
from retarget.inference.foot_lock import FootLockedRetargeter
from tests.figures import tall_and_small

FRAMES = 75


@pytest.fixture(scope="module")
def people(tmp_path_factory):
    folder = tmp_path_factory.mktemp("feet")
    tracks = tall_and_small(FRAMES)
    return {name: write_track(tracks[name], folder / f"{name}.npz") for name in ("tall", "small")}


def test_wrapper_is_lock_feet_of_the_plain_result_in_both_paths(people, tmp_path):
    retargeter = api.load_retargeter(api.PACKAGED_WEIGHTS, device="cpu")
    motion, reference = read_track(people["tall"]), read_track(people["small"])
    codes = retargeter.reference_codes(reference)
    plain = retargeter.retarget(motion, codes)
    locked = FootLockedRetargeter(retargeter).retarget(motion, codes)
    assert locked.equals(lock_feet(plain, motion))
    assert not np.array_equal(locked.joints, plain.joints)  # the figure's feet touch the ground
    out = tmp_path / "a.npz"
    retarget_files(FootLockedRetargeter(retargeter), codes, [people["tall"]], [out], read=read_track, fmt="npz")
    np.testing.assert_array_equal(read_track(out).joints, locked.joints)  # the batch path locks the same


def test_apply_option(people, tmp_path):
    runs = {}
    for flag in ("--foot-lock", "--no-foot-lock", ""):
        out = tmp_path / f"run{flag}.npz"
        result = CliRunner().invoke(app, ["retarget", "apply", str(people["tall"]), "--skeleton", str(people["small"]),
                                          "--out", str(out), "--device", "cpu", "--threads", "1", *flag.split()])
        assert result.exit_code == 0, result.output
        runs[flag] = read_track(out)
    retargeter = api.load_retargeter(api.PACKAGED_WEIGHTS, device="cpu")
    plain = retargeter.retarget(read_track(people["tall"]), retargeter.reference_codes(read_track(people["small"])))
    np.testing.assert_allclose(runs["--no-foot-lock"].joints, plain.joints, atol=1e-3)
    assert np.abs(runs["--foot-lock"].joints - plain.joints).max() > 0.1
    assert runs[""].equals(runs["--foot-lock"])  # on by default


def test_a_driver_at_another_rate_is_locked_on_its_own_frames(people):
    retargeter = api.load_retargeter(api.PACKAGED_WEIGHTS, device="cpu", backend="numpy")
    motion = resample(read_track(people["tall"]), 60.0)
    codes = retargeter.reference_codes(read_track(people["small"]))
    locked = FootLockedRetargeter(retargeter).retarget(motion, codes)
    assert (len(locked), locked.fps) == (len(motion), 60.0)
    assert locked.equals(lock_feet(retargeter.retarget(motion, codes), motion))
