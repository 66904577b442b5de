"""retarget.network.numpy_net: the network evaluated with numpy gives the torch model's outputs.

Random weights for every variant (fast, no files), the shipped weights through their export, and the authors'
released weights against the arrays their own code produced (../shared, skipped when absent).
"""

from __future__ import annotations

import numpy as np
import pytest
import torch

from retarget.network.model import VARIANTS, RetargetNet
from retarget.network.numpy_net import NumpyRetargetNet

TOL = 1e-4  # network units (normalised channels); measured ~3e-6


pytestmark = pytest.mark.usefixtures("one_thread")


def _pair(variant: str, seed: int = 0) -> tuple[RetargetNet, NumpyRetargetNet]:
    torch.manual_seed(seed)
    model = RetargetNet(VARIANTS[variant]).eval()
    with torch.no_grad():  # larger than the default init, so that every layer matters
        for p in model.parameters():
            p.mul_(1.5)
    return model, NumpyRetargetNet(model.config, {k: v.numpy() for k, v in model.state_dict().items()})


def _codes(model: RetargetNet, x: torch.Tensor) -> tuple[torch.Tensor | None, torch.Tensor | None]:
    body = model.encode_body(x) if model.body_encoder is not None else None
    view = model.encode_view(x) if model.view_encoder is not None else None
    return body, view


@pytest.mark.parametrize("variant", list(VARIANTS))
@pytest.mark.parametrize("frames", [16, 40, 120, 256])
def test_every_layer_matches_torch(variant, frames):
    model, net = _pair(variant, seed=frames)
    if frames < model.min_frames:
        pytest.skip(f"the {variant} network takes at least {model.min_frames} frames")
    x = torch.randn(3, 30, frames, generator=torch.Generator().manual_seed(frames))
    xn = x.numpy()
    with torch.no_grad():
        motion = model.encode_motion(x)
        body, view = _codes(model, x)
        decoded = model.decode(motion, body, view)
    np.testing.assert_allclose(net.encode_motion(xn), motion.numpy(), atol=TOL)
    if body is not None:
        np.testing.assert_allclose(net.encode_body(xn), body.numpy(), atol=TOL)
    if view is not None:
        np.testing.assert_allclose(net.encode_view(xn), view.numpy(), atol=TOL)
    codes = [None if c is None else c.numpy() for c in (body, view)]
    np.testing.assert_allclose(net.decode(motion.numpy(), *codes), decoded.numpy(), atol=TOL)
    np.testing.assert_allclose(net.run(xn, *codes), decoded.numpy(), atol=TOL)
    assert net.run(xn, *codes).dtype == np.float32


@pytest.mark.parametrize("variant", list(VARIANTS))
@pytest.mark.parametrize("frames", [16, 40, 120])
def test_the_decoders_backward_pass_is_torch_autograds(variant, frames):
    """decode_backward (what numpy refinement steps with) against autograd through the torch decoder, at lengths
    where the polyphase layers take their plain path (16), the corrected ends (40) and the long middle."""
    model, net = _pair(variant, seed=frames + 1)
    if frames < model.min_frames:
        pytest.skip(f"the {variant} network takes at least {model.min_frames} frames")
    rng = torch.Generator().manual_seed(frames)
    x = torch.randn(2, 30, frames, generator=rng)
    body, view = _codes(model, x)
    motion = model.encode_motion(x).detach().requires_grad_(True)
    weights = torch.randn(2, 30, frames, generator=rng)  # a loss whose gradient is these weights
    (model.decode(motion, body, view) * weights).sum().backward()
    codes = [None if c is None else c.detach().numpy()[:, :, 0] for c in (body, view)]
    kept: list[np.ndarray] = []
    net._decode(motion.detach().numpy().transpose(0, 2, 1), net._first_bias(*codes), kept)
    grad = net.decode_backward(weights.numpy().transpose(0, 2, 1), kept).transpose(0, 2, 1)
    np.testing.assert_allclose(grad, motion.grad.numpy(), atol=TOL * np.abs(motion.grad.numpy()).max())


def test_numpy_refinement_takes_torchs_steps():
    from retarget.inference import numpy_refine, refine

    model, net = _pair("full", seed=5)
    x = torch.randn(3, 30, 96, generator=torch.Generator().manual_seed(5))
    for steps, anchor in ((1, 0.3), (30, 0.3), (10, 0.0)):
        encoded, refined = refine.refined_motion(model, x, steps, 0.02, anchor, 64, 32)
        ours = numpy_refine.refined_motion(net, x.numpy(), steps, 0.02, anchor, 64, 32)
        np.testing.assert_allclose(ours[0].transpose(0, 2, 1), encoded.numpy(), atol=TOL)
        np.testing.assert_allclose(ours[1].transpose(0, 2, 1), refined.numpy(), atol=TOL)
        assert np.abs(refined.numpy() - encoded.numpy()).max() > 10 * TOL  # the steps moved the codes
    body, view = (c[:1].detach() for c in _codes(model, x))
    with torch.no_grad():
        decoded = refine.decode_refined(model, x, body, view, 5, 0.02, 0.3, 64, 32)
    ours = numpy_refine.decode_refined(net, x.numpy(), body.numpy(), view.numpy(), 5, 0.02, 0.3, 64, 32)
    np.testing.assert_allclose(ours, decoded.numpy(), atol=TOL)


def test_static_codes_broadcast_over_the_batch_and_accept_flat_codes():
    model, net = _pair("full")
    x = torch.randn(4, 30, 64, generator=torch.Generator().manual_seed(1))
    with torch.no_grad():
        body, view = _codes(model, x[:1])
        expected = model.decode(model.encode_motion(x), body, view).numpy()
    flat = net.run(x.numpy(), body.numpy()[:, :, 0][0], view.numpy()[0, :, 0])  # [Cb] and [Cv]
    np.testing.assert_allclose(flat, expected, atol=TOL)


def test_codes_must_fit_the_variant():
    _, net = _pair("skeleton")
    x = np.zeros((1, 30, 64), np.float32)
    with pytest.raises(ValueError, match="takes no a view code|takes no"):
        net.run(x, np.zeros((1, 64), np.float32), np.zeros((1, 8), np.float32))
    with pytest.raises(ValueError, match="needs a skeleton code"):
        net.run(x, None, None)
    with pytest.raises(ValueError, match="no view encoder"):
        net.encode_view(x)


def test_parameters_of_another_shape_or_missing_are_refused():
    model, _ = _pair("full")
    params = {k: v.numpy() for k, v in model.state_dict().items()}
    with pytest.raises(ValueError, match="decoder.layers.0.weight"):
        NumpyRetargetNet(VARIANTS["full"], {**params, "decoder.layers.0.weight": np.zeros((128, 150, 7))})
    del params["motion_encoder.layers.1.bias"]
    with pytest.raises(KeyError):
        NumpyRetargetNet(VARIANTS["full"], params)


def test_min_frames_is_the_torch_models():
    for variant in VARIANTS:
        model, net = _pair(variant)
        assert net.min_frames == model.min_frames and net.variant == variant


# ---------------------------------------------------------------------------------------------------------
# The authors' released weights (../shared/official_2dmr): exported to .npz, then their own arrays.


@pytest.fixture(scope="module")
def official_exports(shared_dir, tmp_path_factory):
    from retarget.network.checkpoint import load_official
    from retarget.network.numpy_weights import export_npz, read_npz

    weights = shared_dir / "official_2dmr" / "weights"
    folder = tmp_path_factory.mktemp("official_npz")
    out = {}
    for variant in ("full", "skeleton", "view"):
        npz = export_npz(weights / f"pretrained_{variant}.pth", folder / f"{variant}.npz")
        out[variant] = (load_official(weights / f"pretrained_{variant}.pth"), read_npz(npz))
    return out


@pytest.mark.parametrize("clip", ["tall_man", "small_man"])
def test_authors_weights_reproduce_their_self_reconstruction(official_exports, shared_dir, clip):
    from pose_io.readers import read_track
    from retarget.inference.tracks import prepare_track
    from retarget.network.preprocess import PreprocessConfig, channels_to_joints, joints_to_channels

    torch_weights, numpy_weights = official_exports["full"]
    track = read_track(shared_dir / "openpose_examples" / clip, image_size=(720, 720)).frames(0, 120)
    x = joints_to_channels(prepare_track(track, PreprocessConfig())[None], numpy_weights.stats).astype(np.float32)
    net = numpy_weights.model
    out = net.run(x, net.encode_body(x), net.encode_view(x))
    joints = channels_to_joints(out.astype(np.float64), numpy_weights.stats, np.array([256.0, 256.0]))
    expected = np.load(shared_dir / "official_2dmr" / "parity" / f"full_self_recon_{clip}.npy")
    np.testing.assert_allclose(joints[0].transpose(1, 2, 0), expected, atol=1e-3)
    with torch.no_grad():
        reference = torch_weights.model(torch.from_numpy(x)).numpy()
    np.testing.assert_allclose(out, reference, atol=TOL)


@pytest.mark.parametrize("variant", ["skeleton", "view"])
def test_authors_two_encoder_models_match_torch(official_exports, variant):
    torch_weights, numpy_weights = official_exports[variant]
    x = np.random.default_rng(0).normal(size=(2, 30, 120)).astype(np.float32)
    with torch.no_grad():
        expected = torch_weights.model(torch.from_numpy(x)).numpy()
    net = numpy_weights.model
    codes = (net.encode_body(x), None) if variant == "skeleton" else (None, net.encode_view(x))
    np.testing.assert_allclose(net.run(x, *codes), expected, atol=TOL)
