import numpy as np
import pytest
import torch

from pose_io.clean import smooth_joints
from pose_io.readers import read_track
from retarget.inference.tracks import prepare_track
from retarget.network.checkpoint import load_official
from retarget.network.model import (
    VARIANTS,
    NetworkConfig,
    RetargetNet,
    map_official_state_dict,
    min_frames,
    variant_config,
)
from retarget.network.preprocess import NormStats, PreprocessConfig, channels_to_joints, joints_to_channels

CLIPS = ("tall_man", "small_man")


@pytest.fixture(scope="module")
def official(shared_dir):
    weights = shared_dir / "official_2dmr" / "weights"
    return {v: load_official(weights / f"pretrained_{v}.pth") for v in ("full", "skeleton", "view")}


@pytest.fixture(scope="module")
def raw(shared_dir):
    """The two example clips' first 120 frames in the authors' 512-space."""
    return {
        c: prepare_track(read_track(shared_dir / "openpose_examples" / c, image_size=(720, 720)).frames(0, 120),
                         PreprocessConfig())
        for c in CLIPS
    }


def _input(joints: np.ndarray, stats: NormStats) -> torch.Tensor:
    return joints_to_channels(torch.from_numpy(joints)[None], stats).float()


def test_shapes_of_the_paper_model():
    net = RetargetNet().eval()
    x = torch.randn(3, 30, 64)
    m, b, v = net.encode_motion(x), net.encode_body(x), net.encode_view(x)
    assert m.shape == (3, 128, 8) and b.shape == (3, 16, 1) and v.shape == (3, 8, 1)
    assert net.decode(m, b, v).shape == (3, 30, 64)
    assert net(x).shape == (3, 30, 64)
    assert sum(p.numel() for p in net.parameters()) == 449_206


@pytest.mark.parametrize("variant, params, decoder_in", [("skeleton", 444_814, 192), ("view", 548_030, 160)])
def test_two_encoder_variants(variant, params, decoder_in):
    net = RetargetNet(variant_config(variant))
    assert net.variant == variant
    assert sum(p.numel() for p in net.parameters()) == params
    assert net.decoder.layers[0].in_channels == decoder_in
    x = torch.randn(2, 30, 32)
    assert net(x).shape == x.shape
    missing = "view" if variant == "skeleton" else "skeleton"
    with pytest.raises(ValueError, match=f"no {missing} encoder" if missing == "view" else "no skeleton encoder"):
        (net.encode_view if missing == "view" else net.encode_body)(x)


def test_decode_broadcasts_static_codes_over_batch_and_time():
    net = RetargetNet().eval()
    x = torch.randn(4, 30, 32)
    m = net.encode_motion(x)
    b, v = net.encode_body(x[:1]), net.encode_view(x[:1])
    out = net.decode(m, b, v)
    torch.testing.assert_close(out, net.decode(m, b[:, :, 0].expand(4, -1), v.expand(4, -1, -1)))
    with pytest.raises(ValueError, match="needs a view code"):
        net.decode(m, b, None)


def test_min_frames():
    assert min_frames(VARIANTS["full"]) == 16
    assert min_frames(VARIANTS["view"]) == 32
    net = RetargetNet().eval()
    net(torch.randn(1, 30, 16))
    with pytest.raises(RuntimeError):
        net(torch.randn(1, 30, 8))


def test_unknown_variant_lists_the_valid_ones():
    with pytest.raises(ValueError, match="full, skeleton, view"):
        variant_config("big")


def test_config_dict_round_trip():
    for config in VARIANTS.values():
        assert NetworkConfig.from_dict(config.to_dict()) == config


def test_forward_has_no_data_dependent_python_branches():
    net = RetargetNet().eval()
    traced = torch.fx.symbolic_trace(net)
    x = torch.randn(2, 30, 48)
    torch.testing.assert_close(traced(x), net(x))


def test_official_keys_map_onto_our_layout(shared_dir):
    sd = torch.load(shared_dir / "official_2dmr" / "weights" / "pretrained_full.pth", weights_only=True)
    variant, mapped = map_official_state_dict(sd)
    assert variant == "full"
    assert set(mapped) == set(RetargetNet().state_dict())
    with pytest.raises(ValueError, match="not a state dict"):
        map_official_state_dict({"encoder.weight": torch.zeros(1)})


# Parity with the arrays the authors' code produced (../shared/official_2dmr/parity), within 1e-3 px.


def test_parity_codes(official, raw, shared_dir):
    parity = shared_dir / "official_2dmr" / "parity"
    full = official["full"]
    with torch.no_grad():
        motion = full.model.encode_motion(_input(raw["tall_man"], full.stats))
        body = full.model.encode_body(_input(raw["small_man"], full.stats))
    np.testing.assert_allclose(motion.numpy(), np.load(parity / "full_motion_code_tall_man.npy"), atol=1e-4)
    np.testing.assert_allclose(body.numpy(), np.load(parity / "full_body_code_small_man.npy"), atol=1e-4)


@pytest.mark.parametrize("clip", CLIPS)
def test_parity_self_reconstruction(official, raw, shared_dir, clip):
    full = official["full"]
    with torch.no_grad():
        out = full.model(_input(raw[clip], full.stats))
    joints = channels_to_joints(out.double(), full.stats, torch.tensor([256.0, 256.0], dtype=torch.float64))
    expected = np.load(shared_dir / "official_2dmr" / "parity" / f"full_self_recon_{clip}.npy")
    np.testing.assert_allclose(joints[0].numpy().transpose(1, 2, 0), expected, atol=1e-3)


@pytest.mark.parametrize("motion, skeleton", [("tall_man", "small_man"), ("small_man", "tall_man")])
def test_parity_skeleton_transfer(official, raw, shared_dir, motion, skeleton):
    parity = shared_dir / "official_2dmr" / "parity"
    net = official["skeleton"]
    inputs = {}
    for clip in CLIPS:
        centred = raw[clip] - raw[clip][0, 8] + 256.0  # MidHip of frame 0 at (256, 256)
        np.testing.assert_allclose(centred.transpose(1, 2, 0), np.load(parity / f"skeleton_input_{clip}.npy"), atol=1e-3)
        inputs[clip] = _input(centred, net.stats)
    with torch.no_grad():
        out = net.model.decode(net.model.encode_motion(inputs[motion]), net.model.encode_body(inputs[skeleton]))
    joints = channels_to_joints(out.double(), net.stats, torch.tensor([256.0, 256.0], dtype=torch.float64))[0]
    expected = np.load(parity / f"skeleton_out_{motion}_motion_{skeleton}_skeleton.npy")
    np.testing.assert_allclose(smooth_joints(joints.numpy(), 2.0).transpose(1, 2, 0), expected, atol=1e-3)


def test_official_view_model_loads_and_reconstructs(official, raw):
    net = official["view"]
    assert net.variant == "view"
    x = _input(raw["tall_man"], net.stats)
    with torch.no_grad():
        error = float(((net.model(x) - x) ** 2).mean())
    assert error < 0.1  # a trained autoencoder, not random weights (those give ~1)
