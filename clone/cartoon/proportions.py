"""Holding a cartoon character's proportions: a forward-kinematics fix, and how far a track is from them.

The limbs along the body (head, trunk, upper arms, forearms, thighs, shins) have one 2D length each for a flat
cartoon, and the fix gives them exactly that length in every frame, keeping each limb's direction, walking out
from the root so that a child moves with its parent. The widths (root to hips, neck to shoulders) shrink and
grow as the body turns, which a 2D spec cannot know: the fix keeps the network's width vectors as they are,
and the limb-length error leaves them out.
"""

from __future__ import annotations

import numpy as np

from clone.metrics import limb_error
from pose_io.layouts import JointLayout
from retarget.network.preprocess import LAYOUT, ROOT

WIDTHS: frozenset[frozenset[str]] = frozenset(
    frozenset(pair) for pair in (("neck", "r_shoulder"), ("neck", "l_shoulder"), ("mid_hip", "r_hip"),
                                 ("mid_hip", "l_hip"))
)


def held_limbs(layout: JointLayout = LAYOUT) -> np.ndarray:
    """[L] bool: True for the limbs whose length the fix holds and the error measures (not the widths)."""
    return np.array([frozenset(limb) not in WIDTHS for limb in layout.limbs])


def tree_order(layout: JointLayout = LAYOUT, root: str = ROOT) -> list[tuple[int, int, int]]:
    """The limbs as ``(parent, child, limb index)`` with every parent placed before its children."""
    done, order = {layout.index(root)}, []
    while len(done) < len(layout):
        grown = False
        for i, (a, b) in enumerate(layout.limb_indices):
            for parent, child in ((int(a), int(b)), (int(b), int(a))):
                if parent in done and child not in done:
                    order.append((parent, child, i))
                    done.add(child)
                    grown = True
        if not grown:
            raise ValueError(f"the limbs of {layout.name} do not connect every joint to {root}")
    return order


def hold_lengths(joints: np.ndarray, lengths: np.ndarray, rest: np.ndarray, layout: JointLayout = LAYOUT) -> np.ndarray:
    """Give every held limb its length in every frame (forward kinematics from the root).

    Args:
        joints: [T, J, 2] complete poses (no NaN).
        lengths: [L] target length per limb in ``layout.limbs`` order; NaN = keep that limb's vector.
        rest: [J, 2] a pose whose limb directions stand in where a limb of ``joints`` has no length.
        layout: joint layout.

    Returns:
        [T, J, 2] float64; the root is not moved.
    """
    joints = np.asarray(joints, dtype=np.float64)
    out = np.empty_like(joints)
    root = layout.index(ROOT)
    out[:, root] = joints[:, root]
    for parent, child, i in tree_order(layout):
        vector = joints[:, child] - joints[:, parent]  # [T, 2]
        if not np.isnan(lengths[i]):
            norm = np.linalg.norm(vector, axis=-1, keepdims=True)  # [T, 1]
            fallback = rest[child] - rest[parent]
            fallback = fallback / max(float(np.linalg.norm(fallback)), 1e-9)
            direction = np.where(norm > 1e-6, vector / np.maximum(norm, 1e-6), fallback)
            vector = lengths[i] * direction
        out[:, child] = out[:, parent] + vector
    return out


def proportion_error(joints: np.ndarray, lengths: np.ndarray, height: float, layout: JointLayout = LAYOUT) -> dict:
    """Limb-length error of a track against the character's lengths, the widths left out.

    Args:
        joints: [T, J, 2] poses.
        lengths: [L] the character's limb lengths.
        height: the character's height in pixels.
        layout: joint layout.

    Returns:
        ``{"mean_pct": ..., "per_limb_pct": {"a-b": ...}}``: mean over frames and held limbs of
        ``|length - target| / height * 100`` (:func:`clone.metrics.limb_error`), and the mean per limb.
    """
    targets = np.where(held_limbs(layout), lengths, np.nan)
    _, errors = limb_error(joints, targets, height, layout)  # [T, L], NaN for the widths
    held = held_limbs(layout)
    per_limb = {f"{a}-{b}": float(np.mean(errors[:, i])) for i, (a, b) in enumerate(layout.limbs) if held[i]}
    return {"mean_pct": float(np.mean(errors[:, held])), "per_limb_pct": per_limb}


def displacement(before: np.ndarray, after: np.ndarray, height: float) -> dict[str, float]:
    """How far a fix moved the joints: mean and max joint distance in % of ``height``."""
    dist = np.linalg.norm(np.asarray(after, dtype=np.float64) - before, axis=-1) / height * 100.0  # [T, J]
    return {"mean_pct": float(dist.mean()), "max_pct": float(dist.max())}
