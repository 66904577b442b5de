import pytest
import torch

from retarget.network.preprocess import LAYOUT
from retarget.training.augment import (
    COMBOS,
    AugmentConfig,
    augment_targets,
    clip_time,
    combo_index,
    corrupt_inputs,
    flip_motions,
    roll_views,
    scale_skeletons,
    warp_time,
)


def _windows(b: int = 3, t: int = 16) -> torch.Tensor:
    return torch.randn(b, 8, t, 15, 2, generator=torch.Generator().manual_seed(0)) * 50 + 200


def test_combo_order():
    assert len(COMBOS) == 8 and all(COMBOS[combo_index(*c)] == c for c in COMBOS)


def test_flipping_twice_is_the_identity_and_swaps_sides():
    w = _windows()
    flips = torch.tensor([[True, False], [False, True], [True, True]])
    once = flip_motions(w, flips)
    torch.testing.assert_close(flip_motions(once, flips), w)
    l_wrist, r_wrist = LAYOUT.index("l_wrist"), LAYOUT.index("r_wrist")
    k = combo_index(0, 1, 1)  # motion 0 of sample 0 is flipped
    torch.testing.assert_close(once[0, k, :, l_wrist, 0], -w[0, k, :, r_wrist, 0])
    torch.testing.assert_close(once[0, combo_index(1, 0, 0)], w[0, combo_index(1, 0, 0)])  # motion 1 is not


def test_scaling_follows_the_skeleton():
    w = _windows()
    out = scale_skeletons(w, torch.tensor([[2.0, 3.0]] * 3))
    for k, (_, c, _) in enumerate(COMBOS):
        torch.testing.assert_close(out[:, k], w[:, k] * (2.0 if c == 0 else 3.0))


def test_clip_keeps_the_combinations_aligned():
    t = torch.arange(16, dtype=torch.float32)
    w = t[None, None, :, None, None].expand(4, 8, 16, 15, 2)
    out = clip_time(w, 8, torch.Generator().manual_seed(1))
    assert out.shape == (4, 8, 8, 15, 2)
    starts = out[:, :, 0, 0, 0]
    assert (starts == starts[:, :1]).all()
    torch.testing.assert_close(out[:, :, :, 0, 0] - starts[..., None], torch.arange(8.0).expand(4, 8, 8))


def test_augment_targets_shares_scale_of_one_character_and_flip_of_one_motion():
    w = _windows(t=64)
    ids = torch.tensor([[[0, 5, 1], [1, 5, 2]]] * 3)  # both triples have character 5
    out = augment_targets(w, ids, AugmentConfig(clip_lengths=(64,), flip_prob=0.0, speed_range=(1.0, 1.0), roll_deg=0.0), torch.Generator().manual_seed(2))
    ratio = out / w
    torch.testing.assert_close(ratio, ratio[:, :1, :1, :1, :1].expand_as(ratio))


def test_corruption_noise_and_held_joints():
    joints = torch.arange(10, dtype=torch.float32)[None, :, None, None].expand(2, 10, 15, 2).contiguous()
    g = torch.Generator().manual_seed(0)
    torch.testing.assert_close(corrupt_inputs(joints, 0.0, 0.0, g), joints)
    held = corrupt_inputs(joints, 0.0, 0.5, g)
    assert (held[:, 0] == 0).all()
    assert (held[:, 1:] <= joints[:, 1:]).all() and (held < joints).any()  # dropped frames repeat earlier ones
    assert (held[:, 1:] >= held[:, :-1]).all()
    noisy = corrupt_inputs(joints, 1.0, 0.0, g)
    assert 0.5 < float((noisy - joints).std()) < 1.5


def test_bad_config():
    with pytest.raises(ValueError, match="multiples of 8"):
        AugmentConfig(clip_lengths=(60,))


def test_time_warp_at_speed_one_is_a_clip_and_follows_the_motion():
    w = _windows(t=32)
    g = torch.Generator().manual_seed(1)
    same = warp_time(w, 32, torch.ones(3, 2), g)
    torch.testing.assert_close(same, w)  # full length at speed 1: nothing to move
    ramp = torch.arange(32.0)[None, None, :, None, None].expand(3, 8, 32, 15, 2).clone()
    slow = warp_time(ramp, 16, torch.tensor([[0.5, 1.5]] * 3), g)
    steps = slow[:, :, 1:, 0, 0] - slow[:, :, :-1, 0, 0]  # [3, 8, 15] source frames per output frame
    for k, (m, _, _) in enumerate(COMBOS):
        torch.testing.assert_close(steps[:, k], torch.full_like(steps[:, k], 0.5 if m == 0 else 1.5))
    assert slow.min() >= 0 and slow.max() <= 31  # never reads outside the source


def test_time_warp_reduces_a_speed_that_does_not_fit():
    ramp = torch.arange(16.0)[None, None, :, None, None].expand(1, 8, 16, 15, 2).clone()
    out = warp_time(ramp, 16, torch.tensor([[3.0, 1.0]]), torch.Generator().manual_seed(0))
    assert out[0, 0, -1, 0, 0] <= 15 and torch.isfinite(out).all()


def test_roll_follows_the_view_and_keeps_lengths():
    w = _windows()
    angles = torch.tensor([[0.0, torch.pi / 2]] * 3)
    out = roll_views(w, angles)
    for k, (_, _, v) in enumerate(COMBOS):
        if v == 0:
            torch.testing.assert_close(out[:, k], w[:, k])
        else:  # a quarter turn: (x, y) -> (-y, x)
            torch.testing.assert_close(out[:, k], torch.stack([-w[:, k, ..., 1], w[:, k, ..., 0]], dim=-1))
    bone = lambda x: (x[..., 0, :] - x[..., 1, :]).norm(dim=-1)
    torch.testing.assert_close(bone(out), bone(w))


def test_augment_config_rejects_bad_speed_and_roll():
    with pytest.raises(ValueError):
        AugmentConfig(speed_range=(0.0, 1.0))
    with pytest.raises(ValueError):
        AugmentConfig(roll_deg=90.0)


def test_a_sample_is_mirrored_as_a_whole():
    """Mirroring turns a view of yaw θ into -θ: both motions of a sample must flip together."""
    w = _windows(b=64, t=16)
    ids = torch.tensor([[[0, 1, 2], [3, 4, 5]]] * 64)
    cfg = AugmentConfig(clip_lengths=(16,), scale_range=(1.0, 1.0), speed_range=(1.0, 1.0), roll_deg=0.0)
    out = augment_targets(w, ids, cfg, torch.Generator().manual_seed(3))
    flipped = ~torch.isclose(out, w).reshape(64, 8, -1).all(dim=-1)  # [64, 8]
    assert flipped.any() and not flipped.all()
    assert (flipped == flipped[:, :1]).all()
