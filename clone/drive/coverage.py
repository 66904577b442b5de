"""Pose coverage: which driven frames ask the generator for a pose the reference never showed it.

A reference model learns one person from the poses of one video; a driver who raises her arms, steps wide or
turns her back where the reference never did gets holes and smears. The model keeps the reference's body15 track,
so every drive can measure, frame by frame, how far the pose it asks for is from the nearest pose the reference
made (:func:`pose_coverage`), and name what is new:

* each pose is taken relative to the mid-hip and divided by the reference's height; its distance to a reference
  pose is the RMS over the joints both show, and a frame's distance the smallest over the reference's frames;
* a frame is **outside** when that distance passes a threshold set by the reference itself: 1.5x the 95th
  percentile of each reference frame's distance to the reference frames more than a second away (at least 0.05
  of the height), so a reference that moves a lot tolerates more;
* what is new, for the frames outside: *arms above the head* (a wrist above the nose), *wide stance* (the ankles
  further apart than the widest 2 % of the reference's frames, by a tenth of the height), *back to the camera*
  (:func:`pose_io.details.facing` below -0.3) when the reference shows each in under 5 % of its frames; else
  the part furthest from the nearest reference pose (*arms*, *legs*, *head and trunk*).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from pose_io.details import facing
from pose_io.layouts import BODY15
from pose_io.measures import skeleton_height
from pose_io.track import PoseTrack

MAX_REFERENCE_FRAMES = 600  # reference frames compared against (evenly spaced): bounds time and memory
CHUNK = 256  # driven frames per distance block ([CHUNK, 600, 15, 2] float32: 7 MB)
RARE = 0.05  # a feature the reference shows in fewer frames than this is new to it
MIN_THRESHOLD = 0.05

PARTS = {
    "arms": ("r_shoulder", "r_elbow", "r_wrist", "l_shoulder", "l_elbow", "l_wrist"),
    "legs": ("r_hip", "r_knee", "r_ankle", "l_hip", "l_knee", "l_ankle"),
    "head and trunk": ("nose", "neck", "mid_hip"),
}
FEATURES = ("arms above the head", "wide stance", "back to the camera")


@dataclass(frozen=True)
class Coverage:
    """How much of a drive the reference covers.

    Attributes:
        distance: [T] each driven frame's distance to the nearest reference pose (fraction of the height).
        threshold: the distance beyond which a frame is outside.
        outside: [T] bool.
        parts: what is new in the frames outside -> the share of ALL driven frames that show it, largest first.
    """

    distance: np.ndarray
    threshold: float
    outside: np.ndarray
    parts: dict[str, float] = field(default_factory=dict)

    @property
    def share(self) -> float:
        """The share of driven frames outside the reference's coverage."""
        return float(self.outside.mean()) if len(self.outside) else 0.0

    def line(self) -> str | None:
        """One line for the user when frames fall outside, else None."""
        if not self.outside.any():
            return None
        named = describe_parts(self.parts)
        return (f"coverage: {100 * self.share:.0f}% of the frames ask for poses the reference never showed"
                + (f" ({named})" if named else "")
                + "; expect holes and smears there (the README's 'Filming a good reference' says what to film)")

    def summary(self) -> dict[str, object]:
        """JSON-ready numbers."""
        return {"outside_share": self.share, "threshold": self.threshold, "parts": dict(self.parts),
                "median_distance": float(np.nanmedian(self.distance)) if np.isfinite(self.distance).any() else None}


def describe_parts(parts: dict[str, float]) -> str:
    """``"arms 60%, arms above the head 4%"``: what is new in the uncovered frames, shares under 0.5 % left out."""
    return ", ".join(f"{name} {100 * share:.0f}%" for name, share in parts.items() if share >= 0.005)


def _normalised(joints: np.ndarray, height: float) -> np.ndarray:
    """[T, 15, 2] body15 joints relative to the mid-hip, over ``height``."""
    hip = joints[:, BODY15.index("mid_hip")]
    return (joints - hip[:, None]) / height


def _distances(a: np.ndarray, b: np.ndarray, joints: list[int] | None = None) -> np.ndarray:
    """[len(a), len(b)] RMS distance over the joints both frames show (NaN where none)."""
    if joints is not None:
        a, b = a[:, joints], b[:, joints]
    out = np.empty((len(a), len(b)), dtype=np.float32)
    for start in range(0, len(a), CHUNK):
        block = a[start:start + CHUNK, None] - b[None]  # [C, R, J, 2]
        sq = np.nansum(block**2, axis=-1)  # [C, R, J]
        seen = np.isfinite(block).all(axis=-1)
        count = seen.sum(axis=-1)
        with np.errstate(invalid="ignore", divide="ignore"):
            out[start:start + CHUNK] = np.where(count > 0, np.sqrt(np.where(seen, sq, 0).sum(-1) / count), np.nan)
    return out


def _features(joints: np.ndarray, height: float) -> dict[str, np.ndarray]:
    """[T] bool per named feature of body15 image joints (y down)."""
    idx = BODY15.index
    nose_y = joints[:, idx("nose"), 1]
    wrists_y = joints[:, [idx("r_wrist"), idx("l_wrist")], 1]
    with np.errstate(invalid="ignore"):
        arms_up = (wrists_y < nose_y[:, None]).any(axis=1)
    stance = np.abs(joints[:, idx("l_ankle"), 0] - joints[:, idx("r_ankle"), 0]) / height
    back = facing(joints, BODY15) < -0.3
    return {"arms above the head": arms_up, "wide stance": stance, "back to the camera": back}


def pose_coverage(driven: PoseTrack, reference: PoseTrack) -> Coverage:
    """Measure every driven frame against the poses the reference showed (see the module doc).

    Args:
        driven: the poses the generator is asked for, in the reference's image (body15 first; body31 is fine).
        reference: the reference's body15 track (``ReferenceModel.reference_track``).
    """
    ref_all = reference.to_layout("body15").joints
    drv = driven.to_layout("body15").joints
    height = skeleton_height(ref_all, "body15")
    if not np.isfinite(height) or height <= 0:
        empty = np.zeros(len(drv), dtype=bool)
        return Coverage(np.full(len(drv), np.nan, np.float32), float("nan"), empty)
    keep = np.isfinite(ref_all[:, BODY15.index("mid_hip")]).all(axis=-1)
    ref_frames = np.flatnonzero(keep)
    if len(ref_frames) > MAX_REFERENCE_FRAMES:
        ref_frames = ref_frames[np.linspace(0, len(ref_frames) - 1, MAX_REFERENCE_FRAMES).round().astype(int)]
    ref = _normalised(ref_all[ref_frames], height)
    drv_n = _normalised(drv, height)

    # The reference's own spread: each frame against the frames more than a second away.
    own = _distances(ref, ref)
    apart = np.abs(ref_frames[:, None] - ref_frames[None]) > max(reference.fps, 1.0)
    own = np.where(apart, own, np.nan)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a frame with no frame a second away: NaN
        nearest_own = np.nanmin(own, axis=1) if apart.any() else np.zeros(len(ref))
    spread = float(np.nanpercentile(nearest_own, 95)) if np.isfinite(nearest_own).any() else 0.0
    threshold = max(MIN_THRESHOLD, 1.5 * spread)

    dist = _distances(drv_n, ref)  # [T, R]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        nearest = np.nanmin(np.where(np.isfinite(dist), dist, np.inf), axis=1)
    nearest = np.where(np.isfinite(nearest), nearest, np.nan).astype(np.float32)
    with np.errstate(invalid="ignore"):
        outside = nearest > threshold
    parts: dict[str, float] = {}
    if outside.any():
        parts = _new_parts(drv[outside], drv_n[outside], ref_all[keep], ref, dist[outside], height, len(drv))
    return Coverage(nearest, threshold, outside, parts)


def _new_parts(drv: np.ndarray, drv_n: np.ndarray, ref_all: np.ndarray, ref: np.ndarray, dist: np.ndarray,
               height: float, total: int) -> dict[str, float]:
    """What is new in the outside frames -> share of all ``total`` driven frames, largest first."""
    ref_features = _features(ref_all, height)
    drv_features = _features(drv, height)
    flags = np.zeros((len(drv), len(FEATURES)), dtype=bool)
    for k, name in enumerate(FEATURES):
        if name == "wide stance":
            widest = np.nanpercentile(ref_features[name], 98) if np.isfinite(ref_features[name]).any() else 0.0
            with np.errstate(invalid="ignore"):
                flags[:, k] = drv_features[name] > widest + 0.1
        elif float(np.mean(ref_features[name])) < RARE:
            flags[:, k] = drv_features[name]
    shares = {name: float(flags[:, k].sum()) / total for k, name in enumerate(FEATURES)}
    # Frames no named feature explains: the part furthest from the nearest reference pose.
    rest = ~flags.any(axis=1)
    if rest.any():
        best = np.nanargmin(np.where(np.isfinite(dist[rest]), dist[rest], np.inf), axis=1)
        per_part = np.stack([
            np.nanmean(np.linalg.norm(drv_n[rest][:, [BODY15.index(j) for j in joints]]
                                      - ref[best][:, [BODY15.index(j) for j in joints]], axis=-1), axis=1)
            for joints in PARTS.values()], axis=1)  # [N, parts]
        worst = np.nanargmax(np.where(np.isfinite(per_part), per_part, -np.inf), axis=1)
        for k, name in enumerate(PARTS):
            shares[name] = float((worst == k).sum()) / total
    return dict(sorted(((n, s) for n, s in shares.items() if s > 0), key=lambda item: -item[1]))
