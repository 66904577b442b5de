"""The retargeting network of Aberman et al. 2019: motion, skeleton and view encoders and one decoder.

Shapes (for the paper's settings, ``T`` a multiple of 8):

* ``encode_motion``: ``[B, 30, T] -> [B, 128, T/8]`` (3 strided convolutions, reflection padding).
* ``encode_body``:   ``[B, 30, T] -> [B, 16, 1]`` (pose channels only; 3 conv + max-pool blocks, global max
  pool, 1x1 convolution).
* ``encode_view``:   ``[B, 30, T] -> [B, 8, 1]`` (the same with average pooling).
* ``decode``:        ``([B, 128, T/8], [B, 16, 1], [B, 8, 1]) -> [B, 30, T]`` (3 x [upsample x2, conv]).

The two-encoder variants of the authors' release drop one static encoder and its 1x1 compression:
"skeleton" (max pooling, 64-channel code) and "view" (average pooling, 4 blocks, 32-channel code).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable

import torch
import torch.nn.functional as F
from torch import nn

from retarget.choices import Variant

# The architecture as plain data lives in retarget.network.config (no torch); re-exported here for its users.
from retarget.network.config import VARIANTS, NetworkConfig, min_frames, variant_config
from retarget.network.preprocess import pose_channels

__all__ = [
    "VARIANTS",
    "Decoder",
    "MotionEncoder",
    "NetworkConfig",
    "RetargetNet",
    "StaticEncoder",
    "Variant",
    "map_official_state_dict",
    "min_frames",
    "official_variant",
    "variant_config",
]


def _reflect(x: torch.Tensor, pad: int) -> torch.Tensor:
    return F.pad(x, (pad, pad), mode="reflect")


class MotionEncoder(nn.Module):
    """Stride-2 convolutions: ``[B, C0, T] -> [B, Cn, T / 2^n]``."""

    def __init__(self, channels: tuple[int, ...], kernel: int, negative_slope: float) -> None:
        super().__init__()
        self.pad = (kernel - 2) // 2
        self.slope = negative_slope
        self.layers = nn.ModuleList(
            nn.Conv1d(c_in, c_out, kernel, stride=2) for c_in, c_out in itertools.pairwise(channels)
        )

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        for conv in self.layers:
            x = F.leaky_relu(conv(_reflect(x, self.pad)), self.slope)
        return x


_POOLS: dict[str, tuple[Callable[..., torch.Tensor], Callable[[torch.Tensor], torch.Tensor]]] = {
    # (pool by 2 after each block, global pool over time keeping a length-1 axis)
    "max": (F.max_pool1d, lambda x: x.amax(dim=-1, keepdim=True)),
    "avg": (F.avg_pool1d, lambda x: x.mean(dim=-1, keepdim=True)),
}


class StaticEncoder(nn.Module):
    """Convolution + pooling blocks, a global pool over time, and an optional 1x1 compression.

    ``[B, C0, T] -> [B, code, 1]``.
    """

    def __init__(
        self, channels: tuple[int, ...], code: int | None, pool: str, kernel: int, negative_slope: float
    ) -> None:
        super().__init__()
        self.pad = (kernel - 1) // 2
        self.slope = negative_slope
        self.pool, self.global_pool = _POOLS[pool]
        self.layers = nn.ModuleList(
            nn.Conv1d(c_in, c_out, kernel) for c_in, c_out in itertools.pairwise(channels)
        )
        self.compress = nn.Conv1d(channels[-1], code, 1) if code is not None else nn.Identity()

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        for conv in self.layers:
            x = self.pool(F.leaky_relu(conv(_reflect(x, self.pad)), self.slope), 2)
        return self.compress(self.global_pool(x))


class Decoder(nn.Module):
    """Nearest x2 upsampling + convolution blocks: ``[B, C0, T'] -> [B, Cn, T' * 2^n]``."""

    def __init__(self, channels: tuple[int, ...], kernel: int, dropout: float, negative_slope: float) -> None:
        super().__init__()
        self.pad = (kernel - 1) // 2
        self.slope = negative_slope
        self.dropout = nn.Dropout(dropout)
        self.layers = nn.ModuleList(
            nn.Conv1d(c_in, c_out, kernel) for c_in, c_out in itertools.pairwise(channels)
        )

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        last = len(self.layers) - 1
        for i, conv in enumerate(self.layers):
            x = conv(_reflect(x.repeat_interleave(2, dim=-1), self.pad))  # [B, C, 2T']
            if i < last:
                x = F.leaky_relu(self.dropout(x), self.slope)
        return x


class RetargetNet(nn.Module):
    """Motion / skeleton / view autoencoder of Aberman et al. 2019.

    Args:
        config: architecture (see :data:`VARIANTS`); default the paper's three-encoder model.
    """

    def __init__(self, config: NetworkConfig | None = None) -> None:
        super().__init__()
        self.config = c = config if config is not None else NetworkConfig()
        self.motion_encoder = MotionEncoder(c.motion_channels, c.motion_kernel, c.negative_slope)
        self.body_encoder = (
            StaticEncoder(c.body_channels, c.body_code, "max", c.static_kernel, c.negative_slope)
            if c.body_channels is not None
            else None
        )
        self.view_encoder = (
            StaticEncoder(c.view_channels, c.view_code, "avg", c.static_kernel, c.negative_slope)
            if c.view_channels is not None
            else None
        )
        code = c.motion_channels[-1] + c.body_dim + c.view_dim
        self.decoder = Decoder((code, *c.decoder_channels), c.decoder_kernel, c.dropout, c.negative_slope)

    @property
    def variant(self) -> str:
        return self.config.variant

    @property
    def min_frames(self) -> int:
        """Shortest input (a multiple of the downsampling factor) every layer can take."""
        return min_frames(self.config)

    def encode_motion(self, x: torch.Tensor) -> torch.Tensor:
        """[B, 30, T] -> [B, 128, T/8] motion code (time-varying)."""
        return self.motion_encoder(x)

    def encode_body(self, x: torch.Tensor) -> torch.Tensor:
        """[B, 30, T] -> [B, Cb, 1] skeleton code (from the pose channels only)."""
        if self.body_encoder is None:
            raise ValueError(f"the {self.variant!r} network has no skeleton encoder")
        return self.body_encoder(pose_channels(x))

    def encode_view(self, x: torch.Tensor) -> torch.Tensor:
        """[B, 30, T] -> [B, Cv, 1] view code (from the pose channels only)."""
        if self.view_encoder is None:
            raise ValueError(f"the {self.variant!r} network has no view encoder")
        return self.view_encoder(pose_channels(x))

    def decode(
        self, motion: torch.Tensor, body: torch.Tensor | None = None, view: torch.Tensor | None = None
    ) -> torch.Tensor:
        """Poses from a motion code and static codes.

        Static codes are broadcast over time, and over the batch when they have a batch of 1.

        Args:
            motion: [B, Cm, T'] motion code.
            body: [B or 1, Cb, 1] or [B or 1, Cb] skeleton code (required iff the network has a skeleton encoder).
            view: [B or 1, Cv, 1] or [B or 1, Cv] view code (likewise).

        Returns:
            [B, 30, T' * 8] normalised poses.
        """
        codes = [motion]
        for name, code, present in (
            ("skeleton", body, self.body_encoder is not None),
            ("view", view, self.view_encoder is not None),
        ):
            if present != (code is not None):
                raise ValueError(f"the {self.variant!r} network {'needs' if present else 'takes no'} a {name} code")
            if code is not None:
                code = code.reshape(code.shape[0], -1, 1)  # [B, C] or [B, C, 1] -> [B, C, 1]
                codes.append(code.expand(motion.shape[0], -1, motion.shape[-1]))  # [B, C, T']
        return self.decoder(torch.cat(codes, dim=1))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        """Self-reconstruction ``[B, 30, T] -> [B, 30, T]`` from the input's own codes."""
        body = self.encode_body(x) if self.body_encoder is not None else None
        view = self.encode_view(x) if self.view_encoder is not None else None
        return self.decode(self.encode_motion(x), body, view)


# ---------------------------------------------------------------------------------------------------------
# The authors' released state dicts: their `nn.Sequential` indices -> our layer lists.


def official_variant(state_dict: dict[str, torch.Tensor]) -> str:
    """Which released model a state dict of the authors' code is; ValueError if it is none of them."""
    keys = set(state_dict)
    if "body_encoder.conv1x1.weight" in keys and "view_encoder.conv1x1.weight" in keys:
        return "full"
    static = sorted(k for k in keys if k.startswith("static_encoder.model.") and k.endswith(".weight"))
    if len(static) == 3:
        return "skeleton"
    if len(static) == 4:
        return "view"
    raise ValueError("not a state dict of the authors' 2D-Motion-Retargeting models")


def map_official_state_dict(state_dict: dict[str, torch.Tensor]) -> tuple[str, dict[str, torch.Tensor]]:
    """Rename the authors' keys to :class:`RetargetNet`'s.

    Their blocks are ``nn.Sequential``s: motion encoder [pad, conv, act] (conv at 3i+1), static encoders
    [pad, conv, act, pool] (conv at 4i+1), decoder [up, pad, conv, dropout?, act?] (conv at 5i+2).

    Returns:
        (variant name, state dict for ``RetargetNet(VARIANTS[variant])``).

    Raises:
        ValueError: a key that fits no rule.
    """
    variant = official_variant(state_dict)
    static_target = "body_encoder" if variant == "skeleton" else "view_encoder"
    rules = {
        "mot_encoder": ("motion_encoder", 3, 1),
        "body_encoder": ("body_encoder", 4, 1),
        "view_encoder": ("view_encoder", 4, 1),
        "static_encoder": (static_target, 4, 1),
        "decoder": ("decoder", 5, 2),
    }
    mapped: dict[str, torch.Tensor] = {}
    for key, value in state_dict.items():
        parts = key.split(".")
        module, rest = parts[0], parts[1:]
        if module not in rules:
            raise ValueError(f"unexpected key {key!r} in the authors' state dict")
        target, stride, offset = rules[module]
        if rest[0] == "conv1x1":
            mapped[".".join([target, "compress", *rest[1:]])] = value
        elif rest[0] == "model" and (int(rest[1]) - offset) % stride == 0:
            layer = (int(rest[1]) - offset) // stride
            mapped[".".join([target, "layers", str(layer), *rest[2:]])] = value
        else:
            raise ValueError(f"unexpected key {key!r} in the authors' state dict")
    return variant, mapped
