"""Pose-to-frame networks: a pix2pix-style U-Net generator and a PatchGAN discriminator.

Images are ``[B, C, H, W]`` float in [-1, 1]. The generator sees the pose map of the current frame and the
previous frame (generated while driving, real while training), as in Everybody Dance Now; the discriminator
judges a consecutive pair of frames conditioned on both pose maps, so it can punish flicker as well as
unrealistic frames.

With a background plate (:mod:`clone.model.background`) the generator can leave the static background to it: with
``alpha`` it also gives an alpha mask and its frame is ``alpha * rgb + (1 - alpha) * plate`` (every loss sees
the composite), with ``plate_input`` it also sees the plate.

Both networks are fully convolutional with 4x4 stride-2 convolutions (pix2pix): full-resolution work is
only the first and the last layer, which keeps a 128² generator at about 0.4 GMAC per frame on a CPU.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import torch
from torch import Tensor, nn

# Input channel groups. Built and split in one place (`generator_input`, `discriminator_input`).
POSE_CHANNELS = 3
FRAME_CHANNELS = 3
PLATE_CHANNELS = 3
ALPHA_CHANNELS = 1
# Initial bias of the alpha output before tanh: alpha starts near (tanh(-1) + 1) / 2 = 0.12, mostly plate.
ALPHA_BIAS = -1.0


@dataclass(frozen=True)
class GeneratorConfig:
    """U-Net generator.

    Attributes:
        in_channels: pose map (3) + previous frame (3) + exemplar (3, when it sees one); see :func:`generator_input`.
        out_channels: RGB.
        base_channels: channels after the first down-sampling; doubled per level up to ``max_channels``.
        depth: number of stride-2 levels; the bottleneck is ``size / 2**depth`` pixels wide (>= 2).
        max_channels: channel cap.
        upsample: ``transpose`` (pix2pix's 4x4 transposed convolutions) or ``nearest`` (nearest-neighbour
            upsampling then a 3x3 convolution: no checkerboard patterns, about 1.7x the generator's cost).
        alpha: the last layer also gives an alpha mask, and the frame is the RGB composited over the background
            plate passed to ``forward`` (see :func:`composite`).
        plate_input: the plate passed to ``forward`` is 3 more input channels (after ``in_channels``).
        exemplar: the last 3 of ``in_channels`` are an exemplar (:mod:`clone.model.exemplar`: the reference's own
            frame laid onto the pose), and the head gives one more channel, a blend mask: the RGB is
            ``blend * exemplar + (1 - blend) * painted`` (before the alpha composite), so what lines up is copied
            sharp, not painted.
    """

    in_channels: int = POSE_CHANNELS + FRAME_CHANNELS
    out_channels: int = FRAME_CHANNELS
    base_channels: int = 32
    depth: int = 5
    max_channels: int = 256
    upsample: str = "transpose"
    alpha: bool = False
    plate_input: bool = False
    exemplar: bool = False

    def __post_init__(self) -> None:
        for name in ("in_channels", "out_channels", "base_channels", "depth", "max_channels"):
            if getattr(self, name) < 1:
                raise ValueError(f"GeneratorConfig.{name} must be >= 1, got {getattr(self, name)}")
        if self.upsample not in UPSAMPLERS:
            raise ValueError(f"unknown upsample {self.upsample!r}; valid: {', '.join(sorted(UPSAMPLERS))}")
        if self.exemplar and (self.in_channels < POSE_CHANNELS + FRAME_CHANNELS or self.out_channels != FRAME_CHANNELS):
            raise ValueError("GeneratorConfig.exemplar blends an RGB exemplar (the last 3 input channels) into RGB: "
                             f"in_channels must be >= 6 and out_channels 3, got {self.in_channels}, {self.out_channels}")
        if self.alpha and self.out_channels != FRAME_CHANNELS:
            raise ValueError(f"GeneratorConfig.alpha composites RGB over the plate: out_channels must be "
                             f"{FRAME_CHANNELS}, got {self.out_channels}")

    def min_size(self) -> int:
        """Smallest square input this generator accepts (a 2x2 bottleneck)."""
        return 2 ** (self.depth + 1)

    @property
    def uses_plate(self) -> bool:
        """Whether ``forward`` needs a background plate."""
        return self.alpha or self.plate_input

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict) -> GeneratorConfig:
        return cls(**d)


@dataclass(frozen=True)
class DiscriminatorConfig:
    """PatchGAN discriminator over a consecutive pair.

    Attributes:
        in_channels: pose maps of the previous and current frame, then the two frames (3 + 3 + 3 + 3).
        base_channels: channels of the first layer; doubled per layer up to ``max_channels``.
        num_layers: stride-2 layers (3 gives pix2pix's 70x70 receptive field).
        max_channels: channel cap.
    """

    in_channels: int = 2 * (POSE_CHANNELS + FRAME_CHANNELS)
    base_channels: int = 32
    num_layers: int = 3
    max_channels: int = 256

    def __post_init__(self) -> None:
        for name in ("in_channels", "base_channels", "num_layers", "max_channels"):
            if getattr(self, name) < 1:
                raise ValueError(f"DiscriminatorConfig.{name} must be >= 1, got {getattr(self, name)}")

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict) -> DiscriminatorConfig:
        return cls(**d)


def default_depth(size: int) -> int:
    """Generator depth that brings a ``size``² canvas down to a 4x4 bottleneck (5 at 128²)."""
    if size < 16 or size & (size - 1):
        raise ValueError(f"canvas size must be a power of two >= 16, got {size}")
    return int(math.log2(size)) - 2


def generator_input(pose_map: Tensor, prev_frame: Tensor | None, exemplar: Tensor | None = None) -> Tensor:
    """The generator's input.

    Args:
        pose_map: [B, 3, H, W] pose map of the frame to make, in [-1, 1].
        prev_frame: [B, 3, H, W] previous frame in [-1, 1], or zeros when there is none; None for a generator
            that does not see it.
        exemplar: [B, 3, H, W] the reference's frame laid onto the pose (:mod:`clone.model.exemplar`) in
            [-1, 1], for a generator that sees one.

    Returns:
        [B, 3 to 9, H, W]: the pose map, then the previous frame, then the exemplar.
    """
    parts = [pose_map] + [t for t in (prev_frame, exemplar) if t is not None]
    return parts[0] if len(parts) == 1 else torch.cat(parts, dim=1)


def discriminator_input(pose_prev: Tensor, pose_cur: Tensor, frame_prev: Tensor, frame_cur: Tensor) -> Tensor:
    """The discriminator's input: a consecutive pair conditioned on its pose maps.

    Args:
        pose_prev: [B, 3, H, W] pose map of the previous frame.
        pose_cur: [B, 3, H, W] pose map of the current frame.
        frame_prev: [B, 3, H, W] previous frame.
        frame_cur: [B, 3, H, W] current frame (real or generated).

    Returns:
        [B, 12, H, W].
    """
    return torch.cat([pose_prev, pose_cur, frame_prev, frame_cur], dim=1)


def composite(rgb_alpha: Tensor, plate: Tensor) -> Tensor:
    """The frame of an RGB + alpha output over the background plate: ``alpha * rgb + (1 - alpha) * plate``.

    Args:
        rgb_alpha: [B, 4, H, W] in [-1, 1]: RGB, then alpha (-1 transparent, 1 opaque).
        plate: [B or 1, 3, H, W] background plate in [-1, 1].

    Returns:
        [B, 3, H, W].
    """
    rgb, alpha = rgb_alpha[:, :FRAME_CHANNELS], (rgb_alpha[:, FRAME_CHANNELS:] + 1.0) * 0.5  # [B, 3|1, H, W]
    return alpha * rgb + (1.0 - alpha) * plate


def _channels(base: int, level: int, cap: int) -> int:
    return min(base * 2**level, cap)


def _last_conv(module: nn.Module) -> nn.Conv2d | nn.ConvTranspose2d:
    """The last convolution in ``module`` (the head's output layer, whatever the upsampler)."""
    convs = [m for m in module.modules() if isinstance(m, (nn.Conv2d, nn.ConvTranspose2d))]
    return convs[-1]


class _Down(nn.Sequential):
    def __init__(self, c_in: int, c_out: int, norm: bool) -> None:
        layers: list[nn.Module] = [nn.Conv2d(c_in, c_out, 4, stride=2, padding=1, bias=not norm)]
        if norm:
            layers.append(nn.InstanceNorm2d(c_out, affine=True))
        layers.append(nn.LeakyReLU(0.2, inplace=True))
        super().__init__(*layers)


def _transpose_up(c_in: int, c_out: int, bias: bool) -> nn.Module:
    return nn.ConvTranspose2d(c_in, c_out, 4, stride=2, padding=1, bias=bias)


def _nearest_up(c_in: int, c_out: int, bias: bool) -> nn.Module:
    return nn.Sequential(nn.Upsample(scale_factor=2, mode="nearest"), nn.Conv2d(c_in, c_out, 3, padding=1, bias=bias))


# x2 upsampling layers of the decoder, by GeneratorConfig.upsample.
UPSAMPLERS = {"transpose": _transpose_up, "nearest": _nearest_up}


class _Up(nn.Sequential):
    def __init__(self, c_in: int, c_out: int, upsample: str) -> None:
        super().__init__(
            UPSAMPLERS[upsample](c_in, c_out, False),
            nn.InstanceNorm2d(c_out, affine=True),
            nn.ReLU(inplace=True),
        )


class UNetGenerator(nn.Module):
    """pix2pix U-Net: ``depth`` stride-2 convolutions down, transposed convolutions up, skip connections.

    Level ``i`` (1-based) works at ``H / 2**i`` with ``min(base * 2**(i-1), max)`` channels. The outermost
    layers have no normalisation (pix2pix), the bottleneck none either (a 2x2 instance norm is noise).
    With ``config.alpha`` the head gives one more channel, alpha, whose bias starts at ``ALPHA_BIAS``: the
    first frames are mostly the plate, and G learns where the person covers it.
    """

    def __init__(self, config: GeneratorConfig = GeneratorConfig()) -> None:
        super().__init__()
        self.config = config
        c = [_channels(config.base_channels, i, config.max_channels) for i in range(config.depth)]
        c_in = config.in_channels + (PLATE_CHANNELS if config.plate_input else 0)
        downs = [_Down(c_in, c[0], norm=False)]
        downs += [_Down(c[i - 1], c[i], norm=i < config.depth - 1) for i in range(1, config.depth)]
        self.downs = nn.ModuleList(downs)
        # Up level i maps level i+1's output (concatenated with level i+1's skip, except innermost) to c[i].
        ups = []
        for i in range(config.depth - 2, -1, -1):
            c_in = c[i + 1] if i == config.depth - 2 else 2 * c[i + 1]
            ups.append(_Up(c_in, c[i], config.upsample))
        self.ups = nn.ModuleList(ups)
        c_head = 2 * c[0] if config.depth > 1 else c[0]
        c_out = config.out_channels + (ALPHA_CHANNELS if config.alpha else 0) + (1 if config.exemplar else 0)
        self.head = nn.Sequential(UPSAMPLERS[config.upsample](c_head, c_out, True), nn.Tanh())
        if config.alpha:
            with torch.no_grad():
                _last_conv(self.head).bias[config.out_channels:] = ALPHA_BIAS

    def forward(self, x: Tensor, plate: Tensor | None = None) -> Tensor:
        """The frame.

        Args:
            x: [B, in_channels, H, W] (H, W multiples of 2**depth), see :func:`generator_input`.
            plate: [B or 1, 3, H, W] background plate in [-1, 1]; required when ``config.uses_plate``.

        Returns:
            [B, out_channels, H, W].
        """
        if self.config.uses_plate and plate is None:
            raise ValueError("this generator composites over (or sees) a background plate; pass plate=")
        exemplar = x[:, self.config.in_channels - FRAME_CHANNELS:self.config.in_channels] if self.config.exemplar \
            else None  # [B, 3, H, W]
        if self.config.plate_input:
            x = torch.cat([x, plate.expand(x.shape[0], -1, -1, -1)], dim=1)  # [B, in_channels + 3, H, W]
        skips = []
        for down in self.downs:
            x = down(x)
            skips.append(x)
        x = skips.pop()  # [B, c[depth-1], H/2**depth, W/2**depth]
        for up in self.ups:
            x = up(x)
            x = torch.cat([x, skips.pop()], dim=1)  # [B, 2*c[i], H/2**(i+1), W/2**(i+1)]
        out = self.head(x)  # [B, out_channels (+ 1 alpha) (+ 1 blend), H, W]
        if exemplar is not None:
            blend = (out[:, -1:] + 1.0) * 0.5  # [B, 1, H, W] in [0, 1]
            rgb = blend * exemplar + (1.0 - blend) * out[:, :FRAME_CHANNELS]
            out = torch.cat([rgb, out[:, FRAME_CHANNELS:-1]], dim=1)  # [B, 3 (+ 1 alpha), H, W]
        return composite(out, plate) if self.config.alpha else out


class PatchDiscriminator(nn.Module):
    """pix2pix PatchGAN: a grid of real/fake scores, each seeing a ~70x70 patch (3 layers).

    ``forward`` returns the intermediate activations too, for the feature-matching loss of pix2pixHD.
    """

    def __init__(self, config: DiscriminatorConfig = DiscriminatorConfig()) -> None:
        super().__init__()
        self.config = config
        n, base, cap = config.num_layers, config.base_channels, config.max_channels
        blocks: list[nn.Module] = [_Down(config.in_channels, base, norm=False)]
        for i in range(1, n):
            blocks.append(_Down(_channels(base, i - 1, cap), _channels(base, i, cap), norm=True))
        c_prev, c_last = _channels(base, n - 1, cap), _channels(base, n, cap)
        blocks.append(
            nn.Sequential(
                nn.Conv2d(c_prev, c_last, 4, stride=1, padding=1, bias=False),
                nn.InstanceNorm2d(c_last, affine=True),
                nn.LeakyReLU(0.2, inplace=True),
            )
        )
        blocks.append(nn.Conv2d(c_last, 1, 4, stride=1, padding=1))
        self.blocks = nn.ModuleList(blocks)

    def forward(self, x: Tensor) -> list[Tensor]:
        """Args: x: [B, in_channels, H, W]. Returns: activations of every block, the last [B, 1, h, w] scores."""
        feats = []
        for block in self.blocks:
            x = block(x)
            feats.append(x)
        return feats


GENERATORS: dict[str, type[UNetGenerator]] = {"unet": UNetGenerator}
DISCRIMINATORS: dict[str, type[PatchDiscriminator]] = {"patch": PatchDiscriminator}


def _build(registry: dict, kind: str, name: str, config: object) -> nn.Module:
    try:
        cls = registry[name]
    except KeyError:
        raise ValueError(f"unknown {kind} {name!r}; valid: {', '.join(sorted(registry))}") from None
    return cls(config)


def build_generator(name: str, config: GeneratorConfig) -> UNetGenerator:
    """Generator ``name`` from ``GENERATORS``; an unknown name raises ValueError listing the valid ones."""
    return _build(GENERATORS, "generator", name, config)  # type: ignore[return-value]


def build_discriminator(name: str, config: DiscriminatorConfig) -> PatchDiscriminator:
    """Discriminator ``name`` from ``DISCRIMINATORS``; an unknown name raises ValueError listing the valid ones."""
    return _build(DISCRIMINATORS, "discriminator", name, config)  # type: ignore[return-value]


def lsgan_loss(scores: Tensor, real: bool) -> Tensor:
    """Least-squares GAN loss (Mao et al. 2017) of a score map against the target 1 (real) or 0 (fake)."""
    target = 1.0 if real else 0.0
    return ((scores - target) ** 2).mean()


def feature_matching_loss(fake_feats: list[Tensor], real_feats: list[Tensor]) -> Tensor:
    """pix2pixHD's discriminator feature matching: mean L1 over the intermediate activations (not the scores)."""
    losses = [torch.nn.functional.l1_loss(f, r.detach()) for f, r in zip(fake_feats[:-1], real_feats[:-1])]
    return torch.stack(losses).mean()
