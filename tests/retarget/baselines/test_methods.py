import numpy as np
import pytest

from pose_io import InputError
from pose_io.clean import hold_fill
from pose_io.measures import reference_limb_lengths, skeleton_height
from retarget.baselines.methods import global_scale_retarget, limb_scale_retarget
from retarget.inference.tracks import to_body15
from retarget.network.preprocess import LAYOUT
from tests.figures import tall_and_small


def limb_lengths(joints, quantile=0.95):
    return reference_limb_lengths(joints, LAYOUT, quantile)


@pytest.fixture(scope="module")
def clips():
    """A tall long-legged and a small long-armed person, with a few joints lost as a detector loses them.

    Root and ankles are always seen: the baselines place their gap-filled output at the median of the
    reference's detected root and ankles, so only then is moving a track onto itself exactly the identity.
    """
    people = tall_and_small(always_seen=("mid_hip", "l_ankle", "r_ankle"))
    return {"tall_man": people["tall"], "small_man": people["small"]}


def _filled(track):
    return hold_fill(to_body15(track).joints.astype(np.float64))


@pytest.mark.parametrize("method", [global_scale_retarget, limb_scale_retarget])
def test_onto_itself_is_the_identity(clips, method):
    track = clips["small_man"]
    out = method(track, track)
    np.testing.assert_allclose(out.joints, _filled(track), atol=1e-3)
    assert out.image_size == track.image_size and len(out) == len(track)


def test_global_scaling_matches_the_reference_height(clips):
    out = global_scale_retarget(clips["tall_man"], clips["small_man"])
    small = skeleton_height(_filled(clips["small_man"]))
    assert skeleton_height(out.joints) == pytest.approx(small, rel=0.1)
    # One scale per frame: proportions are the driver's.
    tall = limb_lengths(_filled(clips["tall_man"]))
    ratio = limb_lengths(out.joints) / tall
    assert ratio.std() / ratio.mean() < 0.05


def test_limb_scaling_gives_the_reference_limb_lengths(clips):
    out = limb_scale_retarget(clips["tall_man"], clips["small_man"])
    np.testing.assert_allclose(limb_lengths(out.joints), limb_lengths(_filled(clips["small_man"])), rtol=1e-4)


def test_driver_with_a_joint_never_seen(clips):
    track = clips["small_man"]
    conf = track.confidence.copy()
    conf[:, track.joint_layout.index("nose")] = 0
    with pytest.raises(InputError, match="never detected.*nose"):
        limb_scale_retarget(track.replace(confidence=conf), track)
