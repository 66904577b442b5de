"""Where the retargeting weights shipped with the package live (trained by `clone retarget train`).

Their numpy export is the ``.npz`` beside them (:mod:`retarget.network.numpy_weights`).
"""

from __future__ import annotations

from pathlib import Path

PACKAGED_WEIGHTS = Path(__file__).resolve().parents[1] / "weights" / "clone2d_full.pt"
