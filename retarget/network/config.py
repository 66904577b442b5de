"""Architecture of the retargeting network as plain data (no torch): shared by the torch model
(:mod:`retarget.network.model`) and the numpy one (:mod:`retarget.network.numpy_net`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

from retarget.choices import Variant
from retarget.network.preprocess import NUM_CHANNELS, POSE_CHANNELS


@dataclass(frozen=True)
class NetworkConfig:
    """Architecture of the retargeting network; defaults are the paper's three-encoder model.

    Attributes:
        motion_channels: channel widths of the motion encoder, input first.
        body_channels: widths of the skeleton encoder's convolutions (None: no skeleton encoder).
        body_code: size of the skeleton code after a 1x1 convolution (None: no 1x1, code = last width).
        view_channels: widths of the view encoder's convolutions (None: no view encoder).
        view_code: size of the view code after a 1x1 convolution (None: no 1x1).
        decoder_channels: widths of the decoder after the code concatenation, output last.
        motion_kernel: kernel of the motion encoder's stride-2 convolutions.
        static_kernel: kernel of the static encoders' convolutions.
        decoder_kernel: kernel of the decoder's convolutions.
        dropout: dropout after every decoder convolution but the last.
        negative_slope: slope of the LeakyReLUs.
    """

    motion_channels: tuple[int, ...] = (NUM_CHANNELS, 64, 96, 128)
    body_channels: tuple[int, ...] | None = (POSE_CHANNELS, 32, 48, 64)
    body_code: int | None = 16
    view_channels: tuple[int, ...] | None = (POSE_CHANNELS, 32, 48, 64)
    view_code: int | None = 8
    decoder_channels: tuple[int, ...] = (128, 64, NUM_CHANNELS)
    motion_kernel: int = 8
    static_kernel: int = 7
    decoder_kernel: int = 7
    dropout: float = 0.2
    negative_slope: float = 0.2

    def __post_init__(self) -> None:
        if self.body_channels is None and self.view_channels is None:
            raise ValueError("the network needs a skeleton encoder, a view encoder, or both")
        if self.motion_channels[0] != NUM_CHANNELS or self.decoder_channels[-1] != NUM_CHANNELS:
            raise ValueError(f"the motion encoder input and decoder output must have {NUM_CHANNELS} channels")
        for widths in (self.body_channels, self.view_channels):
            if widths is not None and widths[0] != POSE_CHANNELS:
                raise ValueError(f"static encoders take the {POSE_CHANNELS} pose channels")

    @property
    def variant(self) -> str:
        """"full" (both static encoders), "skeleton" or "view"."""
        if self.body_channels is not None and self.view_channels is not None:
            return "full"
        return "skeleton" if self.body_channels is not None else "view"

    @property
    def body_dim(self) -> int:
        """Size of the skeleton code (0 without a skeleton encoder)."""
        return _code_dim(self.body_channels, self.body_code)

    @property
    def view_dim(self) -> int:
        """Size of the view code (0 without a view encoder)."""
        return _code_dim(self.view_channels, self.view_code)

    @property
    def downsampling(self) -> int:
        """Temporal factor between the input and the motion code."""
        return 2 ** (len(self.motion_channels) - 1)

    def to_dict(self) -> dict[str, Any]:
        """Plain dict (lists for tuples) for checkpoints."""
        return {k: list(v) if isinstance(v, tuple) else v for k, v in dataclasses.asdict(self).items()}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> NetworkConfig:
        """Inverse of :meth:`to_dict`; unknown keys raise ValueError."""
        names = {f.name for f in dataclasses.fields(cls)}
        unknown = set(data) - names
        if unknown:
            raise ValueError(f"unknown network settings: {', '.join(sorted(unknown))}")
        return cls(**{k: tuple(v) if isinstance(v, list) else v for k, v in data.items()})


def _code_dim(widths: tuple[int, ...] | None, code: int | None) -> int:
    if widths is None:
        return 0
    return code if code is not None else widths[-1]



# Keyed by the plain names (they are stored in checkpoints); a Variant looks up the same entry.
VARIANTS: dict[str, NetworkConfig] = {
    Variant.FULL.value: NetworkConfig(),
    Variant.SKELETON.value: NetworkConfig(view_channels=None, view_code=None, body_code=None),
    Variant.VIEW.value: NetworkConfig(
        body_channels=None, body_code=None, view_channels=(POSE_CHANNELS, 64, 96, 128, 32), view_code=None
    ),
}


def variant_config(name: str) -> NetworkConfig:
    """Architecture of a named variant; an unknown name raises ValueError listing the valid ones."""
    try:
        return VARIANTS[name]
    except KeyError:
        raise ValueError(f"unknown network variant {name!r}; valid: {', '.join(VARIANTS)}") from None


def min_frames(config: NetworkConfig) -> int:
    """Shortest input length (a multiple of the downsampling factor) that every layer can take.

    Reflection padding needs a longer signal than the padding, and pooling needs at least one frame left.
    """
    step = config.downsampling
    for frames in range(step, 1 << 20, step):
        length, ok = frames, True
        for _ in range(len(config.motion_channels) - 1):
            ok &= length > (config.motion_kernel - 2) // 2
            length = (length + 2 * ((config.motion_kernel - 2) // 2) - config.motion_kernel) // 2 + 1
        ok &= length >= 1 and 2 * length > (config.decoder_kernel - 1) // 2
        for widths in (config.body_channels, config.view_channels):
            static = frames
            for _ in range(len(widths or ()) - 1):
                ok &= static > (config.static_kernel - 1) // 2 and static >= 2
                static //= 2
        if ok:
            return frames
    raise ValueError("no input length fits this network")
