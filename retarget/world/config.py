"""Settings of a motion world: ``WorldConfig``, the split names, the cache version and folder."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from pose_io.errors import InputError
from retarget.world.camera import CANVAS_SIZE

# Bump when anything that changes the cached arrays changes (rig mapping, head points, sampling...).
WORLD_VERSION = 2
SPLITS: tuple[str, ...] = ("train", "val", "test")


def default_cache_dir() -> Path:
    """``~/.cache/clone2d/world`` (``$CLONE2D_CACHE/world`` when that is set)."""
    from pose_io.atomic import cache_root

    return cache_root() / "world"


@dataclass(frozen=True)
class WorldConfig:
    """Settings of a motion world (all of them enter the cache key).

    Attributes:
        seed: seeds the split of motions and the characters.
        fps: frame rate every clip is resampled to.
        window: window length in frames.
        stride: step between window starts.
        n_train_characters, n_val_characters, n_test_characters: sampled characters per split (test
            also gets every ``NAMED_CHARACTERS`` entry).
        val_fraction, test_fraction: share of each source's frames held out (whole motions).
        canvas_size: (width, height) of the 2D views (framing rule of ``camera.frame_camera``).
        extra_train_characters: training characters beyond the sampled ones, drawn from a random stream of
            their own (val and test characters stay those of a world without them).
        extra_spread: factor on the proportion spread of the extra characters (``sample_skeleton``).
    """

    seed: int = 0
    fps: float = 30.0
    window: int = 64
    stride: int = 32
    n_train_characters: int = 64
    n_val_characters: int = 8
    n_test_characters: int = 8
    val_fraction: float = 0.1
    test_fraction: float = 0.1
    canvas_size: tuple[int, int] = CANVAS_SIZE
    extra_train_characters: int = 0
    extra_spread: float = 1.0

    def __post_init__(self) -> None:
        if self.window < 2 or self.stride < 1:
            raise InputError(f"window must be >= 2 and stride >= 1, got {self.window} and {self.stride}")
        if not self.fps > 0:
            raise InputError(f"fps must be positive, got {self.fps}")
        if min(self.n_train_characters, self.n_val_characters, self.n_test_characters) < 1:
            raise InputError("every split needs at least one character")
        if not (0 <= self.val_fraction < 0.5 and 0 <= self.test_fraction < 0.5):
            raise InputError("val_fraction and test_fraction must be in [0, 0.5)")
        if self.extra_train_characters < 0 or not 0 < self.extra_spread <= 4:
            raise InputError("extra_train_characters must be >= 0 and extra_spread in (0, 4]")


__all__ = ["SPLITS", "WORLD_VERSION", "WorldConfig", "default_cache_dir"]
