"""retarget.training.code_losses: the skeleton codes' ratio, cluster and proportion terms."""

import torch

from retarget.network.model import RetargetNet
from retarget.training.augment import combo_index
from retarget.training.code_losses import skeleton_cluster_loss, skeleton_proportion_loss, skeleton_ratio_loss
from retarget.training.losses import LossConfig, objective
from tests.retarget.training.test_losses import _stats


def test_skeleton_ratio_is_scale_free_and_zero_once_anchors_are_near_their_own_code():
    own, other = torch.tensor([[0.0, 0.0]]), torch.tensor([[4.0, 0.0]])
    codes = torch.stack([own, other])  # [2, B=1, D]: triple 0, triple 1
    near = torch.tensor([[1.0, 0.0], [3.5, 0.0]])  # each anchor 1/3 and 1/7 of the way: below a ratio of 0.5
    assert float(skeleton_ratio_loss(near, codes, 0.5)) == 0.0
    far = torch.tensor([[3.0, 0.0], [1.0, 0.0]])  # each nearer the other triple's code: 3 / 1 - 0.5 each
    torch.testing.assert_close(skeleton_ratio_loss(far, codes, 0.5), torch.tensor(2.5), rtol=1e-5, atol=1e-5)
    torch.testing.assert_close(skeleton_ratio_loss(10 * far, 10 * codes, 0.5), skeleton_ratio_loss(far, codes, 0.5))
    net = RetargetNet().eval()
    x = torch.randn(2, 8, 30, 32)
    losses = objective(net, x, x, _stats(), LossConfig(skeleton_ratio_weight=1.0))
    assert "skeleton_ratio" in losses and float(losses["skeleton_ratio"].detach()) >= 0
    assert "skeleton_ratio" not in objective(net, x, x, _stats(), LossConfig())


def test_skeleton_cluster_is_scale_free_and_takes_the_nearest_other_character():
    # B=1 sample, 2 characters, K=2 windows each, D=2: character 0 around (0, 0), character 1 around (4, 0)
    codes = torch.tensor([[[[-1.0, 0.0], [1.0, 0.0]], [[4.0, -1.0], [4.0, 1.0]]]])  # [1, 2, 2, 2]
    chars = torch.tensor([[3, 5]])
    # spread 1, nearest other centre 4: 1/4 - 0.5 < 0 for both
    assert float(skeleton_cluster_loss(codes, chars, 0.5)) == 0.0
    torch.testing.assert_close(skeleton_cluster_loss(codes, chars, 0.5), skeleton_cluster_loss(10 * codes, chars, 0.5))
    torch.testing.assert_close(skeleton_cluster_loss(codes, chars, 0.1), torch.tensor(0.15))  # 1/4 - 0.1
    # a second sample holds character 3 again, at (3, 0), and character 7 at (9, 0): character 3 is not its own
    # negative (its first centre's nearest other stays character 5 at 4), but character 5's nearest is now the
    # second centre of character 3, 1 away; the second sample's codes have no spread
    again = torch.cat([codes, torch.tensor([[[[3.0, 0.0], [3.0, 0.0]], [[9.0, 0.0], [9.0, 0.0]]]])])  # [2, 2, 2, 2]
    both = torch.tensor([[3, 5], [3, 7]])
    expected = (max(1 / 4 - 0.1, 0) + max(1 / 1 - 0.1, 0) + 0.0 + 0.0) / 4
    torch.testing.assert_close(skeleton_cluster_loss(again, both, 0.1), torch.tensor(expected))
    net = RetargetNet().eval()
    x = torch.randn(2, 8, 30, 32)
    ids = torch.tensor([[[0, 1, 0], [1, 2, 1]], [[2, 3, 0], [3, 1, 1]]])
    losses = objective(net, x, x, _stats(), LossConfig(skeleton_cluster_weight=1.0), ids)
    assert "skeleton_cluster" in losses and float(losses["skeleton_cluster"].detach()) >= 0
    assert "skeleton_cluster" not in objective(net, x, x, _stats(), LossConfig(skeleton_cluster_weight=1.0))


def test_skeleton_proportion_is_scale_free_and_zero_when_codes_follow_the_bodies():
    props = torch.tensor([[0.0, 0.0], [0.0, 0.0], [3.0, 4.0], [6.0, 8.0]])  # samples 0, 1: one character
    codes = torch.cat([props, torch.zeros(4, 3)], dim=1) * 7.0 + 2.0  # the same layout, scaled and moved
    assert float(skeleton_proportion_loss(codes, props)) < 1e-6
    apart = codes.clone()
    apart[1] += 5.0  # one character's two codes apart: the distances no longer follow the bodies
    assert float(skeleton_proportion_loss(apart, props)) > 0.01  # 0.019
    torch.testing.assert_close(skeleton_proportion_loss(3 * apart, props), skeleton_proportion_loss(apart, props))
    net = RetargetNet().eval()
    x = torch.randn(2, 8, 30, 32)
    ids = torch.tensor([[[0, 1, 0], [1, 2, 1]], [[2, 3, 0], [3, 1, 1]]])
    table = torch.randn(4, 17)
    config = LossConfig(skeleton_proportion_weight=2.0)
    losses = objective(net, x, x, _stats(), config, ids, table)
    # codes in the order of the two triples, then samples; characters likewise
    codes = torch.cat([net.encode_body(x[:, 0]).flatten(1), net.encode_body(x[:, combo_index(1, 1, 1)]).flatten(1)])
    expected = 2.0 * skeleton_proportion_loss(codes, table[torch.tensor([1, 3, 2, 1])])
    torch.testing.assert_close(losses["skeleton_proportion"], expected, rtol=1e-4, atol=1e-6)
    assert "skeleton_proportion" not in objective(net, x, x, _stats(), config, ids)  # no table: validation
