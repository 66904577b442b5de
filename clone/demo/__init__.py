"""`clone demo`: the whole pipeline on built-in synthetic pairs with ground truth.

One reference video (a tall, long-legged character dancing, seen from 30°) trains one reference model; three
drivers, each named by what it isolates (``proportions``, ``view``, ``both``), drive it with retargeting and
with Everybody Dance Now's global scaling, and each is measured against its own ground truth (the reference's
character performing the driver's motion, seen by the reference's camera). One overview page sums up the pairs.

- :mod:`~clone.demo.config`: ``DemoConfig``, ``PairConfig``, the shipped ``PAIRS`` and ``QUICK``.
- :mod:`~clone.demo.scenes`: the built-in motions, rendering, the in-frame check of the ground truths.
- :mod:`~clone.demo.folder`: the output folder's safety rules (``MARKER``).
- :mod:`~clone.demo.page`: the overview page.
- :mod:`~clone.demo.run`: ``run_demo`` end to end.
"""

from clone.demo.config import PAIRS, QUICK, DemoConfig, PairConfig
from clone.demo.folder import MARKER, check_out, finish_out, prepare_out
from clone.demo.run import DemoResult, run_demo
from clone.demo.scenes import demo_motions, edge_distance, ground_truth_track

__all__ = [
    "MARKER",
    "PAIRS",
    "QUICK",
    "DemoConfig",
    "DemoResult",
    "PairConfig",
    "check_out",
    "demo_motions",
    "edge_distance",
    "finish_out",
    "ground_truth_track",
    "prepare_out",
    "run_demo",
]
