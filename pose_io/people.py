"""Several people per frame: the raw detections of a source, and following one person through them.

Readers of multi-person formats (OpenPose, COCO results, AlphaPose) return :class:`Detections`; one
person is then followed with :func:`follow_person`:

1. The start is the first frame that has anybody. There the chosen person is ``person=K`` (the K-th
   detection of that frame, in file order, counting only detections with a visible joint) or, by
   default, the most prominent one: largest bounding box of visible joints times mean confidence.
2. Frame to frame, the candidate nearest to the person's last known pose wins. Distance is the mean
   pixel distance over joints visible in both; the last known position of each joint is remembered,
   so a briefly hidden joint still counts. A candidate is accepted only within ``gate`` times the
   person's size (diagonal of the bounding box of the remembered joints); the gate widens with the
   square root of the number of frames since the last match, so tracking recovers after occlusions.
3. A frame with no acceptable candidate gives an all-missing frame; nothing is copied silently.

When the source gives identities (AlphaPose's ``idx`` with pose tracking on), the chosen identity is
followed instead of nearest matching.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from pose_io.errors import InputError
from pose_io.layouts import get_layout

log = logging.getLogger(__name__)

#: Default gate: a match must lie within this fraction of the person's bounding-box diagonal.
DEFAULT_GATE = 0.25


@dataclass(frozen=True, eq=False)
class Detections:
    """Everybody a source found, frame by frame, before one person is chosen.

    Attributes:
        people: per frame a ``[P_t, J, 3]`` float32 array of (x, y, confidence); a missing joint has
            NaN coordinates and confidence 0. Only detections with at least one visible joint are kept.
        layout: joint layout name.
        fps: frames per second stored in the source, or None when the format has none.
        image_size: (width, height) stored in the source, or None when the format has none.
        ids: per frame a ``[P_t]`` int64 array of identities given by the source, or None.
        single: True when each frame holds at most the one person of a track (our own formats), so
            no person needs to be chosen.
        source: the path read, for messages.
    """

    people: tuple[np.ndarray, ...]
    layout: str
    fps: float | None = None
    image_size: tuple[int, int] | None = None
    ids: tuple[np.ndarray, ...] | None = None
    single: bool = False
    source: str = ""

    def __post_init__(self) -> None:
        j = len(get_layout(self.layout))
        if not self.people:
            raise InputError(f"{self.source}: no frames")
        for t, p in enumerate(self.people):
            if p.ndim != 3 or p.shape[1:] != (j, 3):
                raise ValueError(f"{self.source}: frame {t} has people of shape {p.shape}, expected [P, {j}, 3]")
        if self.ids is not None and [len(i) for i in self.ids] != [len(p) for p in self.people]:
            raise ValueError(f"{self.source}: ids do not match people")

    @property
    def num_frames(self) -> int:
        return len(self.people)

    @property
    def counts(self) -> np.ndarray:
        """[T] int number of people (with a visible joint) in each frame."""
        return np.array([len(p) for p in self.people], dtype=np.int64)


@dataclass(frozen=True, eq=False)
class FollowResult:
    """One person followed through :class:`Detections`.

    Attributes:
        joints: [T, J, 2] float32, NaN where missing.
        confidence: [T, J] float32.
        chosen: [T] int64 index into that frame's people, -1 where the person is missing.
        start: first frame with anybody in it (where the person was chosen).
        lost: frames that had people but none acceptable as the followed person.
    """

    joints: np.ndarray
    confidence: np.ndarray
    chosen: np.ndarray
    start: int
    lost: tuple[int, ...]


def _visible(person: np.ndarray) -> np.ndarray:
    """[J] bool: joints of a [J, 3] person with finite coordinates and confidence > 0."""
    return np.isfinite(person[:, :2]).all(axis=1) & (person[:, 2] > 0)


def _bbox_diagonal(xy: np.ndarray) -> float:
    """Diagonal of the bounding box of [N, 2] points (0 for fewer than two)."""
    if len(xy) < 2:
        return 0.0
    span = xy.max(axis=0) - xy.min(axis=0)
    return float(math.hypot(span[0], span[1]))


# A pose sets the person's size only when it has this many visible joints (fewer give a tiny box).
_MIN_SIZE_JOINTS = 3


def _body_size(xy: np.ndarray, detections: Detections) -> float:
    """Bounding-box diagonal of the [N, 2] start pose, or the median over all detections if it is too sparse."""
    if len(xy) >= _MIN_SIZE_JOINTS:
        return _bbox_diagonal(xy)
    sizes = [
        _bbox_diagonal(p[_visible(p), :2]) for frame in detections.people for p in frame
        if _visible(p).sum() >= _MIN_SIZE_JOINTS
    ]
    return max(float(np.median(sizes)) if sizes else 0.0, 1.0)


def prominence(person: np.ndarray) -> float:
    """Bounding-box area of the visible joints times their mean confidence.

    Args:
        person: [J, 3] (x, y, confidence).
    """
    vis = _visible(person)
    if not vis.any():
        return 0.0
    xy = person[vis, :2]
    span = xy.max(axis=0) - xy.min(axis=0)
    return float(span[0] * span[1] * person[vis, 2].mean())


def pose_distance(ref_xy: np.ndarray, ref_known: np.ndarray, person: np.ndarray) -> float:
    """Mean joint distance between a reference pose and a person, over joints known in both.

    Args:
        ref_xy: [J, 2] reference coordinates.
        ref_known: [J] bool, where the reference is known.
        person: [J, 3] candidate (x, y, confidence).

    Returns:
        The mean distance in pixels, or ``inf`` when no joint is known in both.
    """
    both = ref_known & _visible(person)
    if not both.any():
        return math.inf
    return float(np.linalg.norm(person[both, :2] - ref_xy[both], axis=1).mean())


def follow_person(detections: Detections, person: int | None = None, gate: float = DEFAULT_GATE) -> FollowResult:
    """Follow one person through multi-person detections (see the module docstring).

    Args:
        detections: the source's people per frame.
        person: index K of the person to follow in the first frame with people; None picks the most
            prominent one.
        gate: largest accepted mean joint distance, as a fraction of the person's bounding-box diagonal.

    Returns:
        The followed person's joints and confidence, and which detection was taken in each frame.

    Raises:
        InputError: no person in any frame, or ``person`` out of range.
    """
    if gate <= 0:
        raise InputError(f"tracking gate must be positive, got {gate}")
    j = len(get_layout(detections.layout))
    t_len = detections.num_frames
    joints = np.full((t_len, j, 2), np.nan, dtype=np.float32)
    conf = np.zeros((t_len, j), dtype=np.float32)
    chosen = np.full(t_len, -1, dtype=np.int64)
    with_people = np.flatnonzero(detections.counts > 0)
    if len(with_people) == 0:
        raise InputError(f"{detections.source}: no person in any frame")
    start = int(with_people[0])
    k = _first_person(detections, start, person)

    def take(t: int, i: int) -> None:
        p = detections.people[t][i]
        vis = _visible(p)
        joints[t, vis] = p[vis, :2]
        conf[t, vis] = p[vis, 2]
        chosen[t] = i

    if detections.single:  # one person per frame: no choice to make, so all frames at once
        p = np.stack([detections.people[t][0] for t in with_people])  # [N, J, 3]
        vis = np.isfinite(p[..., :2]).all(axis=-1) & (p[..., 2] > 0)  # [N, J]
        joints[with_people] = np.where(vis[..., None], p[..., :2], np.nan)
        conf[with_people] = np.where(vis, p[..., 2], 0.0)
        chosen[with_people] = 0
        return FollowResult(joints, conf, chosen, start, ())

    take(start, k)
    if detections.ids is not None:
        lost = _follow_ids(detections.ids, with_people, start, k, take)
    else:
        lost = _follow_nearest(detections, with_people, start, joints, gate, take)
    if lost:
        log.warning(
            "%s: the followed person is missing in %d of %d frames with people (first: frame %d)",
            detections.source, len(lost), len(with_people), lost[0],
        )
    return FollowResult(joints, conf, chosen, start, tuple(lost))


def _first_person(detections: Detections, start: int, person: int | None) -> int:
    """The index of the followed person among frame ``start``'s people: ``person``, or the most prominent."""
    first = detections.people[start]
    if detections.single and person not in (None, 0):
        raise InputError(f"{detections.source}: holds one person per frame; person {person} does not exist")
    if person is None:
        return int(np.argmax([prominence(p) for p in first]))
    if 0 <= person < len(first):
        return person
    raise InputError(
        f"{detections.source}: person {person} does not exist; frame {start} has {len(first)} "
        f"{'person' if len(first) == 1 else 'people'} (0..{len(first) - 1})"
    )


def _follow_ids(ids: tuple[np.ndarray, ...], with_people: np.ndarray, start: int, k: int,
                take: Callable[[int, int], None]) -> list[int]:
    """Follow the source's own person ids (``Detections.ids``) from person ``k`` of frame ``start``; the frames
    it is missing in."""
    identity = ids[start][k]
    lost: list[int] = []
    for t in with_people[1:]:
        hits = np.flatnonzero(ids[t] == identity)
        if len(hits):
            take(int(t), int(hits[0]))
        else:
            lost.append(int(t))
    return lost


def _follow_nearest(detections: Detections, with_people: np.ndarray, start: int, joints: np.ndarray, gate: float,
                    take: Callable[[int, int], None]) -> list[int]:
    """Follow the nearest pose, frame to frame, within the gate (see the module docstring); the frames it is
    missing in. ``joints`` [T, J, 2] holds what was taken so far (frame ``start``) and is read as it fills."""
    ref_xy = np.where(np.isnan(joints[start]), 0.0, joints[start])
    ref_known = ~np.isnan(joints[start, :, 0])
    size = _body_size(ref_xy[ref_known], detections)
    last = start
    lost: list[int] = []
    for t in with_people[1:]:
        t = int(t)
        dists = [pose_distance(ref_xy, ref_known, p) for p in detections.people[t]]
        best = int(np.argmin(dists))
        limit = gate * size * math.sqrt(t - last)
        if dists[best] <= limit:
            take(t, best)
            vis = ~np.isnan(joints[t, :, 0])
            ref_xy[vis] = joints[t, vis]
            ref_known |= vis
            if vis.sum() >= _MIN_SIZE_JOINTS:
                size = _bbox_diagonal(joints[t, vis])
            last = t
        else:
            lost.append(t)
    return lost
