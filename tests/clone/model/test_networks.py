import pytest
import torch
import torch.nn.functional as F

from clone.model.networks import (
    DISCRIMINATORS,
    GENERATORS,
    DiscriminatorConfig,
    GeneratorConfig,
    PatchDiscriminator,
    UNetGenerator,
    build_discriminator,
    build_generator,
    composite,
    default_depth,
    discriminator_input,
    feature_matching_loss,
    generator_input,
    lsgan_loss,
)


@pytest.fixture(autouse=True)
def _one_thread():
    before = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(before)


def test_generator_shapes_and_range():
    torch.manual_seed(0)
    g = UNetGenerator(GeneratorConfig(base_channels=8, depth=4))
    pose, prev = torch.randn(2, 3, 64, 48), torch.randn(2, 3, 64, 48)
    y = g(generator_input(pose, prev))
    assert y.shape == (2, 3, 64, 48)
    assert y.abs().max() <= 1.0


@pytest.mark.parametrize("upsample", ["transpose", "nearest"])
@pytest.mark.parametrize("depth", [1, 2, 5])
def test_generator_depths_and_upsamplers(depth, upsample):
    g = UNetGenerator(GeneratorConfig(base_channels=4, depth=depth, max_channels=16, upsample=upsample))
    size = GeneratorConfig(depth=depth).min_size()
    assert g(torch.zeros(1, 6, size, size)).shape == (1, 3, size, size)


def test_discriminator_features_and_patch_scores():
    d = PatchDiscriminator(DiscriminatorConfig(base_channels=8, num_layers=3))
    x = discriminator_input(*(torch.randn(2, 3, 64, 64) for _ in range(4)))
    assert x.shape == (2, 12, 64, 64)
    feats = d(x)
    assert len(feats) == 5
    assert feats[-1].shape == (2, 1, 6, 6)  # 64 -> 32 -> 16 -> 8 -> 7 -> 6 (pix2pix's PatchGAN)


def test_same_seed_same_network_and_deterministic_output():
    cfg = GeneratorConfig(base_channels=8, depth=3)
    torch.manual_seed(3)
    a = UNetGenerator(cfg).eval()
    torch.manual_seed(3)
    b = UNetGenerator(cfg).eval()
    x = torch.randn(1, 6, 32, 32)
    with torch.no_grad():
        ya, ya2, yb = a(x), a(x), b(x)
    assert torch.equal(ya, ya2)
    assert torch.equal(ya, yb)
    torch.manual_seed(4)
    c = UNetGenerator(cfg).eval()
    with torch.no_grad():
        assert not torch.equal(c(x), ya)


def test_registries_and_unknown_names():
    assert build_generator("unet", GeneratorConfig(depth=2)).__class__ is GENERATORS["unet"]
    assert build_discriminator("patch", DiscriminatorConfig()).__class__ is DISCRIMINATORS["patch"]
    with pytest.raises(ValueError, match="valid: unet"):
        build_generator("resnet", GeneratorConfig())
    with pytest.raises(ValueError, match="valid: patch"):
        build_discriminator("multiscale", DiscriminatorConfig())


def test_config_round_trip_and_validation():
    cfg = GeneratorConfig(base_channels=16, depth=4)
    assert GeneratorConfig.from_dict(cfg.to_dict()) == cfg
    assert DiscriminatorConfig.from_dict(DiscriminatorConfig().to_dict()) == DiscriminatorConfig()
    with pytest.raises(ValueError):
        GeneratorConfig(depth=0)
    with pytest.raises(ValueError, match="valid: nearest, transpose"):
        GeneratorConfig(upsample="bicubic")
    assert default_depth(128) == 5 and default_depth(32) == 3 and default_depth(512) == 7
    for bad in (100, 8, 0):
        with pytest.raises(ValueError, match="power of two"):
            default_depth(bad)


def test_losses_known_values():
    assert lsgan_loss(torch.ones(2, 1, 3, 3), True) == 0
    assert lsgan_loss(torch.ones(2, 1, 3, 3), False) == 1
    assert lsgan_loss(torch.full((1, 1, 2, 2), 0.5), True) == pytest.approx(0.25)
    feats = [torch.randn(1, 4, 8, 8), torch.randn(1, 1, 4, 4)]
    assert feature_matching_loss(feats, feats) == 0
    shifted = [feats[0] + 0.5, feats[1] + 100.0]  # the score map is not part of feature matching
    assert feature_matching_loss(shifted, feats) == pytest.approx(0.5)


def test_one_adam_step_lowers_l1_on_a_tiny_batch():
    torch.manual_seed(0)
    g = UNetGenerator(GeneratorConfig(base_channels=8, depth=3))
    x = torch.randn(2, 6, 32, 32)
    target = torch.rand(2, 3, 32, 32) * 2 - 1
    opt = torch.optim.Adam(g.parameters(), lr=2e-4, betas=(0.5, 0.999))
    before = F.l1_loss(g(x), target)
    opt.zero_grad()
    before.backward()
    opt.step()
    with torch.no_grad():
        after = F.l1_loss(g(x), target)
    assert after < before


def test_composite_puts_opaque_rgb_over_the_plate():
    rgb, plate = torch.rand(2, 3, 8, 8) * 2 - 1, torch.rand(1, 3, 8, 8) * 2 - 1
    alpha = torch.full((2, 1, 8, 8), -1.0)
    alpha[1, :, :4] = 1.0  # the top half of the second sample is opaque
    out = composite(torch.cat([rgb, alpha], dim=1), plate)
    assert out.shape == (2, 3, 8, 8)
    torch.testing.assert_close(out[0], plate[0])
    torch.testing.assert_close(out[1, :, :4], rgb[1, :, :4])
    torch.testing.assert_close(out[1, :, 4:], plate[0, :, 4:])
    torch.testing.assert_close(composite(torch.cat([rgb, alpha * 0], dim=1), plate), 0.5 * (rgb + plate))


@pytest.mark.parametrize("upsample", ["transpose", "nearest"])
def test_alpha_generator_composites_over_the_plate(upsample):
    torch.manual_seed(0)
    cfg = GeneratorConfig(base_channels=4, depth=3, max_channels=16, upsample=upsample, alpha=True)
    g = UNetGenerator(cfg).eval()
    x, plate = torch.randn(2, 6, 32, 32), torch.rand(1, 3, 32, 32) * 2 - 1
    with torch.no_grad():
        y = g(x, plate)
        assert y.shape == (2, 3, 32, 32) and y.abs().max() <= 1.0
        # It starts mostly transparent (ALPHA_BIAS): much nearer the plate than a plain generator's frame.
        plain = UNetGenerator(GeneratorConfig(base_channels=4, depth=3, max_channels=16, upsample=upsample)).eval()
        assert (y - plate).abs().mean() < 0.5 * (plain(x) - plate).abs().mean()
        # A transparent head gives the plate exactly, whatever the input.
        head = [m for m in g.head.modules() if isinstance(m, (torch.nn.Conv2d, torch.nn.ConvTranspose2d))][-1]
        head.weight[3:] = 0.0
        head.bias[3:] = -50.0
        torch.testing.assert_close(g(x, plate), plate.expand(2, -1, -1, -1))
    with pytest.raises(ValueError, match="plate"):
        g(x)


def test_plate_input_generator_sees_the_plate():
    torch.manual_seed(0)
    g = UNetGenerator(GeneratorConfig(base_channels=4, depth=3, max_channels=16, plate_input=True)).eval()
    assert g.downs[0][0].in_channels == 9
    x = torch.randn(2, 6, 32, 32)
    with torch.no_grad():
        a, b = g(x, torch.zeros(1, 3, 32, 32)), g(x, torch.ones(1, 3, 32, 32))
    assert a.shape == (2, 3, 32, 32) and not torch.allclose(a, b)
    assert GeneratorConfig(plate_input=True).uses_plate and not GeneratorConfig().uses_plate
    with pytest.raises(ValueError, match="out_channels must be 3"):
        GeneratorConfig(alpha=True, out_channels=4)
    # Older configs (no plate fields) read as generators without a plate.
    old = {k: v for k, v in GeneratorConfig().to_dict().items() if k not in ("alpha", "plate_input")}
    assert GeneratorConfig.from_dict(old) == GeneratorConfig()


def test_default_generator_width_follows_the_canvas_and_stored_runs_keep_theirs():
    from clone.train_ref import TrainConfig

    # Issue #12: 16 channels from 256² up (2.1-2.8x faster there at -0.005 SSIM), 32 below.
    assert TrainConfig(size=128).generator_config().base_channels == 32
    assert TrainConfig(size=256).generator_config().base_channels == 16
    assert TrainConfig(size=256, base_channels=24).base_channels == 24
    # A run stored with the old 256² default (32) rebuilds its own generator, not today's default.
    stored = TrainConfig(size=256, base_channels=32).to_dict()
    assert TrainConfig.from_dict(stored).generator_config().base_channels == 32
    assert TrainConfig.from_dict(TrainConfig(size=512).to_dict()) == TrainConfig(size=512)
