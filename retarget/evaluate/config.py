"""What an evaluation measures (:class:`EvalConfig`) and the shape of what it runs (:data:`Method`)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from pose_io.track import PoseTrack
from retarget.world.camera import MAX_PITCH

Method = Callable[[PoseTrack, PoseTrack], PoseTrack]  # (motion track, reference track) -> retargeted track
Progress = Callable[[int, int], None]  # progress(done, total)
PROBE_ROW = "proportion probe"  # the silhouettes row of the proportion probe (EvalConfig.probe_steps)


@dataclass(frozen=True)
class EvalConfig:
    """What is evaluated.

    Attributes:
        pairs: cases per source (the split, and the extra clips if any).
        length: frames of an evaluated case.
        reference_length: frames of a reference window.
        seed: seeds every choice of cases and of the silhouette windows.
        max_pitch: cameras get a pitch drawn uniformly in +-max_pitch degrees.
        max_yaw: cameras A and B are view bins within +-max_yaw degrees of the front (90: all 13, the paper's
            protocol; 45: the views of most videos, those cloning meets).
        code_samples: motions, characters and views each in a silhouette grid (``code_samples^3`` windows).
        code_grids: silhouette grids, each a new draw of motions and characters (grid 0 is the one earlier
            versions drew alone); their mean and its standard error are reported, as one grid of six characters
            moves by several hundredths with the characters drawn.
        probe_steps: training steps of a proportion probe (:mod:`retarget.evaluate.probe`) scored on the same
            grids as the skeleton codes (0: none).
        noise: detector noise: every joint of the driver and reference tracks the methods see is moved by
            Gaussian noise of this std, as a fraction of that person's height (0 = clean; real OpenPose tracks
            measure about 0.002-0.006). The truth stays clean.
        turns: also score the turn cases (:mod:`retarget.evaluate.turns`): ``pairs`` cases of the split's windows
            each turned by 90-360 degrees, and ``pairs`` cases of its windows that turn by more than 90 degrees
            as captured (when it has any).
    """

    pairs: int = 500
    length: int = 64
    reference_length: int = 64
    seed: int = 0
    max_pitch: float = MAX_PITCH
    max_yaw: float = 90.0
    code_samples: int = 6
    code_grids: int = 10
    probe_steps: int = 0
    noise: float = 0.0
    turns: bool = True

    def __post_init__(self) -> None:
        if self.pairs < 1 or self.length < 8 or self.reference_length < 8:
            raise ValueError("pairs must be >= 1 and length, reference_length >= 8")
        if self.code_samples < 2 or self.code_grids < 1 or self.probe_steps < 0 or self.max_pitch < 0:
            raise ValueError("code_samples must be >= 2, code_grids >= 1, probe_steps >= 0 and max_pitch >= 0")
        if not 0 <= self.max_yaw <= 90:
            raise ValueError("max_yaw must be in [0, 90] degrees")
        if not 0 <= self.noise <= 0.1:
            raise ValueError("noise must be in [0, 0.1] of the height")


# The paper's protocol; a shared default is safe as the config is frozen.
DEFAULT_CONFIG = EvalConfig()
