"""Paints: skin and cloth colours with patterns, and a :class:`~clone.synth.appearance.Look` per body part.

A :class:`Paint` colours pixels from texture coordinates laid along a body part (``u``, metres along its
axis) and around it (``v``, metres of arc), so a pattern moves with the body. :class:`Materials` arranges
a look's paints per body part once per video; limbs get :data:`Bands` (a shirt sleeve ending at the
elbow, shorts ending above the knee).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from clone.synth.appearance import Look

PLAIN, STRIPES, CHECKS = 0, 1, 2
PATTERN_CODES = {"plain": PLAIN, "stripes": STRIPES, "checks": CHECKS}


def rgb(c: Sequence[int]) -> np.ndarray:
    """[3] float32 RGB 0..255 from any three numbers."""
    return np.asarray(c, dtype=np.float32)


@dataclass(frozen=True)
class Paint:
    """A cloth or skin colour with an optional pattern (``period`` metres along and around the body)."""

    base: np.ndarray  # [3] float32 RGB 0..255
    accent: np.ndarray  # [3] float32
    pattern: int = PLAIN
    period: float = 1.0

    @staticmethod
    def solid(colour: Sequence[int]) -> Paint:
        """One plain colour."""
        return Paint(rgb(colour), rgb(colour))

    def colours(self, u: np.ndarray, v: np.ndarray | None) -> np.ndarray:
        """[h, w, 3] (or broadcastable [1, 1, 3]) colours at texture coordinates ``u`` (along), ``v`` (around)."""
        if self.pattern == PLAIN:
            return self.base[None, None]
        if self.pattern == STRIPES or v is None:
            mask = np.remainder(u, self.period) < 0.4 * self.period
        else:
            mask = (np.floor(u * (2.0 / self.period)) + np.floor(v * (2.0 / self.period))) % 2 == 1
        return np.where(mask[..., None], self.accent, self.base)


Bands = tuple[tuple[float, Paint], ...]  # (t_end, paint) along a primitive's axis, the last one to t=1 and beyond


def banded(bands: Bands, t: np.ndarray, u: np.ndarray, v: np.ndarray | None) -> np.ndarray:
    """[h, w, 3] colours of ``bands`` at axis fractions ``t`` [h, w] and texture coordinates ``u``, ``v``."""
    colours = bands[-1][1].colours(u, v)
    for t_end, paint in reversed(bands[:-1]):
        colours = np.where((t < t_end)[..., None], paint.colours(u, v), colours)
    return colours


@dataclass(frozen=True)
class Materials:
    """A look's paints, arranged per body part (built once per video)."""

    skin: Paint
    hair: Paint
    shirt: Paint
    bottom: Paint
    belt: Paint
    shoes: Paint
    upper_arm: Bands
    forearm: Bands
    thigh: Bands
    shin: Bands

    @staticmethod
    def of(look: Look) -> Materials:
        """The paints of ``look``: sleeves and trouser legs as bands along the limbs."""
        skin = Paint.solid(look.skin)
        shirt = Paint(rgb(look.top), rgb(look.top_accent), PATTERN_CODES[look.pattern], look.pattern_period)
        bottom = Paint.solid(look.bottom)
        upper_arm: Bands = {"long": ((1.0, shirt),), "short": ((0.55, shirt), (1.0, skin)),
                            "none": ((1.0, skin),)}[look.sleeves]
        forearm: Bands = ((0.96, shirt), (1.0, skin)) if look.sleeves == "long" else ((1.0, skin),)
        thigh: Bands = ((0.6, bottom), (1.0, skin)) if look.bottom_style == "shorts" else (
            ((1.0, bottom),) if look.bottom_style == "trousers" else ((1.0, skin),))
        shin: Bands = ((1.0, bottom),) if look.bottom_style == "trousers" else ((1.0, skin),)
        return Materials(skin=skin, hair=Paint.solid(look.hair), shirt=shirt, bottom=bottom,
                         belt=Paint.solid(look.belt), shoes=Paint.solid(look.shoes),
                         upper_arm=upper_arm, forearm=forearm, thigh=thigh, shin=shin)
