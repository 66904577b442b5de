"""Turn cases for `clone retarget eval`: motions whose facing changes by more than 90 degrees within a case.

Two sources, each scored for every method like the split's own windows:

* :class:`TurnedMotions`: every window of a source given a whole-body turn of 90-360 degrees either way
  (:mod:`retarget.world.turns`), drawn per window from the evaluation seed. The turn is applied to the 3D motion
  before A's and B's replays are projected, so the truth (A's motion on B's skeleton through camera B) turns
  exactly as the driver does. Reference windows stay as captured.
* :class:`CapturedTurns`: the source's own windows that already turn by more than 90 degrees (few: the world built
  from the shipped collection holds four in its test split and five in validation).
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from retarget.world.split import WindowLabel
from retarget.world.turns import apply_turn, draw_turn, facing_change

TURN_DEGREES = 90.0  # a case "turns" when its facing changes by more than this
TURN_RANGE = (90.0, 360.0)


class MotionSource(Protocol):
    """What evaluation reads of a source of motions (a ``WorldSplit`` or ``ClipMotions``)."""

    window_labels: tuple[WindowLabel, ...]

    @property
    def num_motions(self) -> int: ...

    def window3d(self, motion: int, character: int, length: int | None = None, offset: int = 0) -> np.ndarray: ...


class TurnedMotions:
    """``source``'s windows, each turned by its own random turn (the same on every character).

    Args:
        source: the motions.
        seed: seeds each window's turn (with the window index and the length asked for).
        angle_range: the turns' angles, degrees.
    """

    def __init__(self, source: MotionSource, seed: int, angle_range: tuple[float, float] = TURN_RANGE) -> None:
        self.source = source
        self.seed = seed
        self.angle_range = angle_range
        self.window_labels = source.window_labels

    @property
    def num_motions(self) -> int:
        return self.source.num_motions

    def window3d(self, motion: int, character: int, length: int | None = None, offset: int = 0) -> np.ndarray:
        """[length, 18, 3] the source's window, turned (the turn spans the ``length`` frames asked for)."""
        pos = self.source.window3d(motion, character, length, offset)
        turn = draw_turn(np.random.default_rng([self.seed, 7727, motion, len(pos)]), len(pos), self.angle_range)
        return apply_turn(pos, turn)


class CapturedTurns:
    """The windows of ``source`` whose captured facing changes by more than :data:`TURN_DEGREES` over their first
    ``length`` frames (seen on ``character``, default the first: a replay turns alike on every character)."""

    def __init__(self, source: MotionSource, length: int, character: int = 0) -> None:
        self.source = source
        turning = []
        for m, label in enumerate(source.window_labels):
            if label.clip_frames - label.start < length:
                continue
            if facing_change(source.window3d(m, character, length)) > TURN_DEGREES:
                turning.append(m)
        self._index = turning
        self.window_labels = tuple(source.window_labels[m] for m in turning)

    @property
    def num_motions(self) -> int:
        return len(self._index)

    def window3d(self, motion: int, character: int, length: int | None = None, offset: int = 0) -> np.ndarray:
        return self.source.window3d(self._index[motion], character, length, offset)


__all__ = ["TURN_DEGREES", "CapturedTurns", "TurnedMotions"]
