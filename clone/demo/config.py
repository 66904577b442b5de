"""What `clone demo` runs: one reference and the driver pairs that isolate the paper's claims.

The paper's performance-cloning figure claims that global scaling gives the reference the driver's proportions
and shows it from the driver's side, while retargeting keeps the reference's own proportions and view. Each pair
isolates one part of it: ``proportions`` (a child's body, the reference's camera), ``view`` (the reference's own
body, a camera 60° away, on the other side) and ``both``.

Every ground truth (the reference's character performing the driver's motion, seen by the reference's camera)
stays inside the frame for its whole clip: the motion world's framing puts the clip's first root at the centre
of the frame and the ground at 90 % of its height at 0.36 x height pixels per metre, so the clips are windows of
motions that stay near where they start and keep their hands below 2.4 m (``clone.demo.scenes.edge_distance``
checks it on every run; ``tests/clone/test_demo_config.py`` for the shipped configurations).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field


@dataclass(frozen=True)
class PairConfig:
    """One driver of the demo and what it isolates.

    Attributes:
        name: the pair's folder and section name.
        title: what the pair tests, one line.
        character: the driver's named character (``clone synth characters``).
        yaw: the driver's camera yaw in degrees, relative to the clip's mean facing (+ = its left side).
        motion: key of the built-in motion (:func:`clone.demo.scenes.demo_motions`).
        start: first frame of the clip in the motion.
        frames: frames of the clip.
    """

    name: str
    title: str
    character: str
    yaw: float
    motion: str
    start: int
    frames: int


# The reference is seen from +30° (its left side); the other side is -30°: 60° apart. The motions are ones the
# shipped retargeting network never trained on (clone/data/SOURCES.md).
PAIRS: tuple[PairConfig, ...] = (
    PairConfig("proportions", "a child's dance on the tall reference, seen by the reference's camera (+30°)",
               "child", 30.0, "arabesque", 45, 100),
    PairConfig("view", "the reference's own body filmed from its other side (-30°, 60° away)",
               "tall_long_legs", -30.0, "washing", 0, 100),
    PairConfig("both", "a child filmed from the other side (-30°): proportions and view at once",
               "child", -30.0, "arabesque", 0, 100),
)  # fmt: skip


@dataclass(frozen=True)
class DemoConfig:
    """Sizes, budgets and scenes of a demo run.

    Attributes:
        render_size: side of the rendered videos in pixels.
        model_size: canvas of the pose-to-frame generator.
        minutes: CPU training budget of the reference model (the stage that sets the demo's length).
        reference_character: named character of the reference.
        reference_motion: key of its built-in motion.
        reference_yaw: the reference's camera yaw in degrees (every ground truth uses it too).
        reference_frames: frames of the reference video (None: the whole motion).
        pairs: the drivers, each with its own ground truth.
        edge_margin: every ground-truth joint must stay this share of the frame away from its edges (the
            head and hands reach past the joints).
        seed: training seed.
    """

    render_size: int = 256
    model_size: int = 256
    minutes: float = 5.5
    reference_character: str = "tall_long_legs"
    reference_motion: str = "reference"
    reference_yaw: float = 30.0
    reference_frames: int | None = None
    pairs: tuple[PairConfig, ...] = field(default=PAIRS)
    edge_margin: float = 0.04
    seed: int = 0

    def __post_init__(self) -> None:
        names = [p.name for p in self.pairs]
        if not names or len(set(names)) != len(names):
            raise ValueError(f"a demo needs pairs with distinct names, got {names}")


def shortened(pairs: tuple[PairConfig, ...], frames: int) -> tuple[PairConfig, ...]:
    """The same pairs cut to their first ``frames`` frames (a window of a window stays inside the frame)."""
    return tuple(dataclasses.replace(p, frames=min(p.frames, frames)) for p in pairs)


QUICK = DemoConfig(model_size=128, minutes=1.0, reference_frames=300, pairs=shortened(PAIRS, 60))
