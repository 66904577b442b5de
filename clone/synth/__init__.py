"""Synthetic performers: a motion-world motion replayed on a character with a look, rendered from a view.

Rendering the reference character with the driver's motion and the reference's view gives the ground
truth of a cloning run; ``clone synth``, the demo and the benchmarks use it.

- :mod:`~clone.synth.appearance`: ``Look``, ``BodyShape``, ``Backdrop``; ``get_look``, ``look_from_seed``,
  ``get_character`` (skeleton + look by name or seed).
- :mod:`~clone.synth.paint`: colours and patterns per body part.
- :mod:`~clone.synth.raster`, :mod:`~clone.synth.cylinder`: ``Rasterizer``, the shaded, depth-tested
  primitives.
- :mod:`~clone.synth.background`: ``make_background`` (wall and floor).
- :mod:`~clone.synth.body`: ``PerformerRenderer``, a performer from projected joints and a look.
- :mod:`~clone.synth.performance`: ``render_performance``, ``save_performance`` (frames, poses, meta),
  ``performance_background`` (the empty background as the video shows it).
"""

from clone.synth.appearance import (
    NAMED_LOOKS,
    Backdrop,
    BodyShape,
    Look,
    get_character,
    get_look,
    look_from_seed,
)
from clone.synth.background import make_background
from clone.synth.body import PerformerRenderer
from clone.synth.paint import Paint
from clone.synth.performance import performance_background, render_performance, save_performance
from clone.synth.raster import Rasterizer

__all__ = [
    "NAMED_LOOKS",
    "Backdrop",
    "BodyShape",
    "Look",
    "Paint",
    "PerformerRenderer",
    "Rasterizer",
    "get_character",
    "get_look",
    "look_from_seed",
    "make_background",
    "performance_background",
    "render_performance",
    "save_performance",
]
