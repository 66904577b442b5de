import numpy as np
import pytest
import torch
import torch.nn.functional as F

from retarget.network.model import RetargetNet, variant_config
from retarget.network.preprocess import LAYOUT, NormStats, joints_to_channels
from retarget.training.augment import combo_index
from retarget.training.losses import (
    LossConfig,
    ablation_config,
    foot_velocity,
    objective,
    trajectory_error,
    used_combos,
)


def _stats() -> NormStats:
    rng = np.random.default_rng(0)
    return NormStats(rng.normal(0, 10, (15, 2)), rng.uniform(2, 20, (15, 2)))


def test_combinations_per_variant():
    assert used_combos(RetargetNet(), cross=True) == list(range(8))
    assert used_combos(RetargetNet(), cross=False) == [0, 7]
    skeleton = used_combos(RetargetNet(variant_config("skeleton")), cross=True)
    assert skeleton == [combo_index(0, 0, 0), combo_index(0, 1, 0), combo_index(1, 0, 1), combo_index(1, 1, 1)]
    view = used_combos(RetargetNet(variant_config("view")), cross=True)
    assert view == [combo_index(0, 0, 0), combo_index(0, 0, 1), combo_index(1, 1, 0), combo_index(1, 1, 1)]


@pytest.mark.parametrize("name, keys", [
    ("full", {"rec", "cross", "foot", "triplet", "total"}),
    ("no-triplet", {"rec", "cross", "foot", "total"}),
    ("recon-triplet", {"rec", "foot", "triplet", "total"}),
])
def test_ablations_choose_the_terms(name, keys):
    torch.manual_seed(0)
    net = RetargetNet().eval()
    x = torch.randn(2, 8, 30, 32)
    losses = objective(net, x, x, _stats(), ablation_config(name))
    assert set(losses) == keys
    torch.testing.assert_close(losses["total"], sum(v for k, v in losses.items() if k != "total"))


def test_reconstruction_terms_are_the_mse_of_the_decoded_combinations():
    torch.manual_seed(0)
    net = RetargetNet().eval()
    inputs, targets = torch.randn(2, 8, 30, 32), torch.randn(2, 8, 30, 32)
    losses = objective(net, inputs, targets, _stats(), LossConfig(triplet=False, foot_weight=0.0))
    x1, x2 = inputs[:, 0], inputs[:, 7]
    expected_cross = 0.0
    for k in range(1, 7):
        m, c, v = k >> 2 & 1, k >> 1 & 1, k & 1
        source = (x1, x2)
        out = net.decode(net.encode_motion(source[m]), net.encode_body(source[c]), net.encode_view(source[v]))
        expected_cross += ((out - targets[:, k]) ** 2).mean()
    own = ((net(x1) - targets[:, 0]) ** 2).mean() + ((net(x2) - targets[:, 7]) ** 2).mean()
    torch.testing.assert_close(losses["rec"], own)
    torch.testing.assert_close(losses["cross"], expected_cross)


def test_triplet_anchors_share_one_factor_with_their_positive():
    torch.manual_seed(0)
    net = RetargetNet().eval()
    x = torch.randn(3, 8, 30, 32)
    losses = objective(net, x, x, _stats(), LossConfig(cross=False, foot_weight=0.0))
    encoders = {"m": net.encode_motion, "b": net.encode_body, "v": net.encode_view}
    # (code, anchor combination, triple of the positive): e.g. (m1, c2, v2) has triple 0's motion.
    cases = [("m", (0, 1, 1), 0), ("m", (1, 0, 0), 1), ("b", (1, 0, 1), 0), ("b", (0, 1, 0), 1),
             ("v", (1, 1, 0), 0), ("v", (0, 0, 1), 1)]
    expected = 0.0
    for code, anchor, positive in cases:
        enc = encoders[code]
        own, other = enc(x[:, 0 if positive == 0 else 7]), enc(x[:, 7 if positive == 0 else 0])
        a = enc(x[:, combo_index(*anchor)])
        expected += F.triplet_margin_loss(a.flatten(1), own.flatten(1), other.flatten(1), margin=0.3)
    torch.testing.assert_close(losses["triplet"], 0.1 * expected)


def test_foot_velocity_is_the_global_ankle_velocity():
    t = torch.arange(6, dtype=torch.float64)
    joints = torch.zeros(1, 6, 15, 2, dtype=torch.float64)
    joints[..., 0] = (3.0 * t)[None, :, None]  # everything walks 3 px per frame
    joints[0, :, LAYOUT.index("l_ankle"), 0] = 10.0  # the left ankle stays planted
    stats = NormStats(np.zeros((15, 2)), np.full((15, 2), 2.0))
    v = foot_velocity(joints_to_channels(joints, stats), stats)  # [1, 5, 2 feet (l, r), 2]
    torch.testing.assert_close(v[0, :, 1, 0], torch.full((5,), 1.5, dtype=torch.float64))
    torch.testing.assert_close(v[0, :, 0, 0], torch.zeros(5, dtype=torch.float64))


def test_trajectory_error_ignores_a_translation_and_sees_a_drift():
    truth = torch.randn(3, 30, 32)
    same = truth.clone()
    same[:, 28:, 0] += 5.0  # one jump in the first frame: the whole path moves by a constant
    torch.testing.assert_close(trajectory_error(same, truth), torch.zeros(3), atol=1e-6, rtol=0)
    drift = truth.clone()
    drift[:, 28] += 0.1  # a small bias per frame adds up over the window
    error = trajectory_error(drift, truth)
    t = torch.arange(32.0)
    expected = ((0.1 * (t + 1) - (0.1 * (t + 1)).mean()) ** 2).mean() / 2 / 32
    torch.testing.assert_close(error, torch.full((3,), float(expected)))


def test_trajectory_term_joins_the_objective_when_weighted():
    net = RetargetNet().eval()
    x = torch.randn(2, 8, 30, 32)
    losses = objective(net, x, x, _stats(), LossConfig(trajectory_weight=0.5))
    assert "trajectory" in losses and float(losses["trajectory"].detach()) > 0
    assert "trajectory" not in objective(net, x, x, _stats(), LossConfig())


def test_cycle_term_is_the_round_trip_through_the_next_windows_codes():
    from retarget.training.losses import cycle, self_reconstruction

    torch.manual_seed(0)
    net = RetargetNet().eval()
    x = torch.randn(3, 30, 32)
    back = cycle(net, x)
    # window 0 goes through window 2's codes (cyclic batch order) and back through its own
    moved = net.decode(net.encode_motion(x[:1]), net.encode_body(x[2:]), net.encode_view(x[2:]))
    expected = net.decode(net.encode_motion(moved), net.encode_body(x[:1]), net.encode_view(x[:1]))
    torch.testing.assert_close(back[:1], expected)
    losses = self_reconstruction(net, x, x, _stats(), LossConfig(foot_weight=0.0, cycle_weight=2.0))
    torch.testing.assert_close(losses["cycle"], 2.0 * ((back - x) ** 2).mean())
    assert "cycle" not in self_reconstruction(net, x[:1], x[:1], _stats(), LossConfig(foot_weight=0.0, cycle_weight=2.0))
    # off by default
    assert "cycle" not in self_reconstruction(net, x, x, _stats(), LossConfig(foot_weight=0.0))
