"""Exemplars: a frame of the reference itself in a pose near the one asked, moved onto it, as more input for the
generator.

A pose map says where the limbs go, not what the lace, the face or the shoes look like; a generator trained for
minutes paints them as a blur. The reference's own frames hold them. For each frame to make, the nearest of a
bank of reference frames (in pose, after centring on the hips and scaling by the torso) is laid onto the asked
pose by a similarity (least squares over the body15 joints both show; the head again by its face points,
:func:`with_head`) and given to the generator as three more input channels, which it blends into what it paints
(:class:`clone.model.networks.GeneratorConfig` ``exemplar``): it copies what lines up and paints the rest.

- **The bank** (:class:`ExemplarBank`): up to ``max_count`` usable frames of the reference chosen to cover its
  poses (farthest-point sampling), stored in the model as JPEG with their joints (a few MB at 256²).
- **Training** (:func:`training_choices`): each frame gets one of its ``k`` nearest bank frames at least ``gap``
  frames away from it in the video (the held-out frames of a drive are never in the bank either), within its own
  group (one performer of a prior).
- **Driving** (:func:`drive_choices`): the nearest bank frame of each driven pose, kept from frame to frame
  until another is clearly nearer (so the exemplar does not flick between two near ones).
- **Limbs it gets wrong** (:func:`stray_limbs`): a limb of the exemplar as laid on that lies far from the asked
  one (an arm down where the pose raises it) is blacked out where it lies and where it is asked, so the generator
  paints it; training blacks out a random limb in a share of the samples (``AugmentConfig.exemplar_drop``) so that
  it learns to.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np
import torch

from pose_io.layouts import get_layout

# Body15 joints (the first 15 of every layout the generator draws) place and scale the exemplar.
BODY = 15
_NECK, _MID_HIP = 1, 8
# The face points of the body31 layout (nose, eyes, ears, mouth corners) lay the head on; its disc's radius is this
# share of the asked torso (neck to mid-hip; the face's radius is about a quarter of it).
FACE = tuple(get_layout("body31").index(n) for n in ("nose", "r_eye", "l_eye", "r_ear", "l_ear", "mouth_right",
                                                     "mouth_left"))
HEAD_RADIUS = 0.5
# The exemplar's turn onto the asked pose at most (radians): people stand upright.
MAX_TURN = 0.5
# Squared distance (in torsos) a joint counts for when one pose shows it and the other does not.
MISSING_PENALTY = 0.25
# Bank frames a model keeps at most (each a JPEG of the canvas) and their JPEG quality.
MAX_BANK = 256
JPEG_QUALITY = 92
# Training: an exemplar is one of the K nearest bank frames at least GAP_SECONDS away in the video.
TRAIN_K = 3
GAP_SECONDS = 1.0
# Driving: the exemplar changes only when another bank frame is nearer by this share of the current distance.
STICKINESS = 0.2
# Limb chains of body15 (right arm, left arm, right leg, left leg; shoulder or hip first). Where a joint of a chain
# laid on lies more than STRAY torsos from the asked one (arms down in the exemplar, raised in the pose asked), the
# exemplar is blacked out along the chain as laid on and as asked, LIMB_RADIUS torsos either side (the end joint's
# hand or foot a disc of HAND_RADIUS): the generator paints that limb itself instead of copying a wrong one.
LIMBS = ((2, 3, 4), (5, 6, 7), (9, 10, 11), (12, 13, 14))
STRAY = 0.35
LIMB_RADIUS = 0.16
HAND_RADIUS = 0.3


def pose_features(joints: np.ndarray) -> np.ndarray:
    """[N, J, 2] canvas joints (NaN where missing) -> [N, J, 2] centred on the hips, in torso lengths (NaN kept).

    The torso (neck to mid-hip) sets the scale; where a frame lacks it, the median torso of the others does.
    """
    joints = np.asarray(joints, dtype=np.float64)
    centre = joints[:, _MID_HIP]  # [N, 2]
    torso = np.linalg.norm(joints[:, _NECK] - centre, axis=-1)  # [N]
    good = np.isfinite(torso) & (torso > 1e-3)
    fallback = float(np.median(torso[good])) if good.any() else 1.0
    torso = np.where(good, torso, fallback)
    # a frame without hips is centred on its visible joints (one without any stays NaN)
    seen = np.isfinite(joints).all(-1, keepdims=True)  # [N, J, 1]
    count = seen.sum(1)  # [N, 1]
    mean = np.where(seen, joints, 0.0).sum(1) / np.maximum(count, 1)
    centre = np.where(np.isfinite(centre), centre, np.where(count > 0, mean, np.nan))
    return ((joints - centre[:, None]) / torso[:, None, None]).astype(np.float32)


def pose_distances(query: np.ndarray, bank: np.ndarray, chunk: int = 128) -> np.ndarray:
    """[Q, K] distances between pose features (:func:`pose_features`): the mean squared joint distance over the
    joints both show, plus :data:`MISSING_PENALTY` for each joint only one of them shows (``chunk`` queries at a
    time, so memory stays flat with the number of queries)."""
    if len(query) > chunk:
        return np.concatenate([pose_distances(query[s:s + chunk], bank, chunk) for s in range(0, len(query), chunk)])
    q_ok, b_ok = np.isfinite(query).all(-1), np.isfinite(bank).all(-1)  # [Q, J], [K, J]
    q, b = np.where(q_ok[..., None], query, 0.0), np.where(b_ok[..., None], bank, 0.0)
    both = q_ok[:, None] & b_ok[None]  # [Q, K, J]
    diff = ((q[:, None] - b[None]) ** 2).sum(-1)  # [Q, K, J]
    shared = both.sum(-1)
    one = (q_ok[:, None] ^ b_ok[None]).sum(-1)
    mean = np.where(both, diff, 0.0).sum(-1) / np.maximum(shared, 1)
    return (mean + MISSING_PENALTY * one / query.shape[1]).astype(np.float32)


def farthest_points(features: np.ndarray, count: int) -> np.ndarray:
    """Indices of ``count`` of ``features`` [N, J, 2] that cover them (greedy farthest-point sampling from the
    first), sorted; all of them when there are no more than ``count``."""
    n = len(features)
    if n <= count:
        return np.arange(n)
    chosen = [0]
    nearest = pose_distances(features, features[:1])[:, 0]
    for _ in range(count - 1):
        pick = int(np.argmax(nearest))
        chosen.append(pick)
        nearest = np.minimum(nearest, pose_distances(features, features[pick:pick + 1])[:, 0])
    return np.sort(np.asarray(chosen))


def fit_onto(src: np.ndarray, dst: np.ndarray, joints: list[int] | None = None) -> np.ndarray:
    """[2, 3] the similarity (scale, a rotation of at most :data:`MAX_TURN` radians, shift) that lays ``src``
    [J, 2] joints onto ``dst`` by least squares over the joints both show (of ``joints``, default the body15
    ones); the identity with fewer than two."""
    pick = list(range(BODY)) if joints is None else joints
    src, dst = np.asarray(src, np.float64)[pick], np.asarray(dst, np.float64)[pick]
    ok = np.isfinite(src).all(-1) & np.isfinite(dst).all(-1)
    if ok.sum() < 2:
        return np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    p, q = src[ok], dst[ok]
    pc, qc = p.mean(0), q.mean(0)
    p, q = p - pc, q - qc
    spread = float((p ** 2).sum())
    if spread < 1e-6:
        return np.array([[1.0, 0.0, qc[0] - pc[0]], [0.0, 1.0, qc[1] - pc[1]]])
    dot = float((p * q).sum())
    cross = float((p[:, 0] * q[:, 1] - p[:, 1] * q[:, 0]).sum())
    angle = float(np.clip(np.arctan2(cross, dot), -MAX_TURN, MAX_TURN))
    cos, sin = np.cos(angle), np.sin(angle)
    scale = float(np.clip((dot * cos + cross * sin) / spread, 0.5, 2.0))  # the best scale at that angle
    rot = scale * np.array([[cos, -sin], [sin, cos]])
    return np.concatenate([rot, (qc - rot @ pc)[:, None]], axis=1)


def transform(joints: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """[J, 2] ``joints`` moved by ``matrix`` [2, 3] (NaN kept)."""
    joints = np.asarray(joints, np.float64)
    return joints @ matrix[:, :2].T + matrix[:, 2]


def stray_limbs(laid: np.ndarray, asked: np.ndarray) -> list[int]:
    """Indices into :data:`LIMBS` of the chains of the exemplar's joints as laid on (``laid`` [J, 2]) that stray
    from ``asked`` [J, 2]: a joint both show more than :data:`STRAY` torsos (of the asked pose) apart."""
    torso = float(np.linalg.norm(asked[_NECK] - asked[_MID_HIP]))
    if not np.isfinite(torso) or torso < 1.0:
        return []
    out = []
    for c, chain in enumerate(LIMBS):
        d = np.linalg.norm(laid[list(chain)] - asked[list(chain)], axis=-1)
        if np.nanmax(np.where(np.isfinite(d), d, 0.0)) > STRAY * torso:
            out.append(c)
    return out


def limb_mask(size: int, torso: float, chains: list[np.ndarray]) -> np.ndarray:
    """[S, S] bool, the band around each of ``chains`` (each [L, 2] canvas joints, NaN skipped): segments
    :data:`LIMB_RADIUS` torsos either side, a disc of :data:`HAND_RADIUS` at the chain's end."""
    mask = np.zeros((size, size), np.uint8)
    half, hand = max(1, round(LIMB_RADIUS * torso)), max(1, round(HAND_RADIUS * torso))
    for chain in chains:
        points = [p for p in np.asarray(chain, np.float64) if np.isfinite(p).all()]
        ends = [(round(float(x)), round(float(y))) for x, y in np.clip(points, -4 * size, 5 * size)]
        for a, b in itertools.pairwise(ends):
            cv2.line(mask, a, b, 1, thickness=2 * half + 1)
        if ends:
            cv2.circle(mask, ends[-1], hand, 1, thickness=-1)
    return mask.astype(bool)


def warp_onto(image: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """[S, S, 3] uint8 ``image`` moved by ``matrix`` [2, 3] (its border repeated where it uncovers the canvas)."""
    size = image.shape[0]
    return cv2.warpAffine(image, matrix, (size, size), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)


def with_head(body: np.ndarray, image: np.ndarray, src: np.ndarray, dst: np.ndarray) -> np.ndarray:
    """``body`` (``image`` laid onto ``dst`` by the body's joints) with the head laid on by its own face points
    inside a soft disc around the asked face (a head turns and tilts apart from the torso); ``body`` as it is
    where ``src`` and ``dst`` [J, 2] share fewer than three face points (a body15 layout has only the nose)."""
    if len(dst) <= max(FACE):
        return body
    shared = [i for i in FACE if np.isfinite(src[i]).all() and np.isfinite(dst[i]).all()]
    if len(shared) < 3:
        return body
    torso = float(np.linalg.norm(dst[_NECK] - dst[_MID_HIP]))
    if not np.isfinite(torso) or torso < 1.0:
        return body
    radius = HEAD_RADIUS * torso
    cx, cy = np.asarray(dst[shared], np.float64).mean(0)
    size = body.shape[0]
    x0, x1 = int(max(0, np.floor(cx - radius))), int(min(size, np.ceil(cx + radius)))
    y0, y1 = int(max(0, np.floor(cy - radius))), int(min(size, np.ceil(cy + radius)))
    if x1 <= x0 or y1 <= y0:
        return body
    head = warp_onto(image, fit_onto(src, dst, shared))
    yy, xx = np.mgrid[y0:y1, x0:x1]
    # 1 within 70 % of the radius, falling to 0 at it
    weight = np.clip((radius - np.hypot(xx - cx, yy - cy)) / (0.3 * radius), 0.0, 1.0)[..., None]
    out = body.copy()
    out[y0:y1, x0:x1] = (weight * head[y0:y1, x0:x1] + (1.0 - weight) * body[y0:y1, x0:x1] + 0.5).astype(np.uint8)
    return out


@dataclass
class ExemplarBank:
    """Reference frames the generator's exemplars come from.

    Attributes:
        images: [K, S, S, 3] uint8 RGB frames on the canvas.
        joints: [K, J, 2] float32 their joints on the canvas (the pose maps' layout), NaN where missing.
        frames: [K] int64 their frame numbers in the reference video.
    """

    images: np.ndarray
    joints: np.ndarray
    frames: np.ndarray

    def __post_init__(self) -> None:
        self.features = pose_features(self.joints)
        torsos = np.linalg.norm(self.joints[:, _NECK] - self.joints[:, _MID_HIP], axis=-1)
        torsos = torsos[np.isfinite(torsos)]
        # the torso a pose without neck or hips is blacked out by (its limbs' band width)
        self.torso = float(np.median(torsos)) if len(torsos) else float("nan")

    def __len__(self) -> int:
        return len(self.frames)

    def exemplar(self, k: int, joints: np.ndarray, drop: tuple[int, ...] = ()) -> np.ndarray:
        """[S, S, 3] uint8 bank frame ``k`` laid onto ``joints`` [J, 2] (canvas pixels): the body by its body15
        joints, and the head by its face points where both show three or more (:func:`with_head`); black along
        the limbs that stray from the asked ones (:func:`stray_limbs`) and the chains of :data:`LIMBS` indexed
        by ``drop`` (training: the generator learns to paint a limb where the exemplar shows none)."""
        matrix = fit_onto(self.joints[k], joints)
        out = with_head(warp_onto(self.images[k], matrix), self.images[k], self.joints[k], joints)
        laid = transform(self.joints[k], matrix)
        blank = sorted(set(stray_limbs(laid, joints)) | set(drop))
        if not blank:
            return out
        torso = float(np.linalg.norm(joints[_NECK] - joints[_MID_HIP]))
        if not np.isfinite(torso) or torso < 1.0:
            torso = self.torso
        if not np.isfinite(torso) or torso < 1.0:
            return out
        chains = [pose[list(LIMBS[c])] for c in blank for pose in (laid, joints)]
        out = out.copy()
        out[limb_mask(out.shape[0], torso, chains)] = 0
        return out

    def to_storable(self) -> dict[str, Any]:
        """What the model file keeps: JPEG bytes per frame, joints, frame numbers."""
        jpegs = []
        for image in self.images:
            ok, data = cv2.imencode(".jpg", cv2.cvtColor(image, cv2.COLOR_RGB2BGR),
                                    [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY])
            if not ok:
                raise ValueError("could not encode an exemplar frame as JPEG")
            jpegs.append(torch.from_numpy(data.reshape(-1).copy()))
        return {"jpeg": jpegs, "joints": torch.from_numpy(np.ascontiguousarray(self.joints, np.float32)),
                "frames": torch.from_numpy(np.asarray(self.frames, np.int64))}

    @classmethod
    def from_storable(cls, entry: dict[str, Any], size: int) -> ExemplarBank:
        """The bank of a model file (see :meth:`to_storable`), checked against the canvas ``size``.

        Raises:
            ValueError, TypeError: the entry is damaged.
        """
        if not isinstance(entry, dict) or not isinstance(entry.get("jpeg"), list):
            raise TypeError("exemplars entry is not a dict of jpeg frames, joints and frame numbers")
        joints, frames = entry["joints"].numpy(), entry["frames"].numpy()
        if not (len(entry["jpeg"]) == len(joints) == len(frames)) or not len(frames):
            raise ValueError("exemplars: frames, joints and frame numbers differ in count")
        images = []
        for data in entry["jpeg"]:
            image = cv2.imdecode(np.asarray(data.numpy(), np.uint8), cv2.IMREAD_COLOR)
            if image is None or image.shape != (size, size, 3):
                raise ValueError(f"exemplars: a frame does not decode to the {size}x{size} canvas")
            images.append(cv2.cvtColor(image, cv2.COLOR_BGR2RGB))
        return cls(np.stack(images), joints.astype(np.float32), frames.astype(np.int64))


def choose_bank(frames: np.ndarray, joints: np.ndarray, usable: np.ndarray, max_count: int = MAX_BANK
                ) -> ExemplarBank:
    """The bank of a reference: up to ``max_count`` of its usable frames covering its poses.

    Args:
        frames: [N, S, S, 3] uint8 frames on the canvas (may be memory-mapped).
        joints: [N, J, 2] their joints on the canvas.
        usable: [N] bool, frames with a usable pose.
        max_count: the bank's size at most.
    """
    candidates = np.flatnonzero(usable)
    picks = candidates[farthest_points(pose_features(joints[candidates]), max_count)]
    every = len(picks) == len(frames)  # all of them (a prior's performers): the frames themselves, not a copy
    images = frames if every else np.stack([np.asarray(frames[i]) for i in picks])
    return ExemplarBank(images, np.asarray(joints[picks], np.float32), picks.astype(np.int64))


def training_choices(bank: ExemplarBank, joints: np.ndarray, gap: int, k: int = TRAIN_K,
                     groups: np.ndarray | None = None) -> np.ndarray:
    """[N, k] for each frame of ``joints`` [N, J, 2], its ``k`` nearest bank frames at least ``gap`` frames away
    from it and in its own group (``groups`` [N] int, e.g. the performer of each frame; one group when None);
    -1 where fewer qualify."""
    n = len(joints)
    groups = np.zeros(n, np.int64) if groups is None else np.asarray(groups, np.int64)
    features = pose_features(joints)
    out = np.full((n, k), -1, np.int64)
    bank_groups = groups[bank.frames]
    for group in np.unique(groups):
        rows, cols = np.flatnonzero(groups == group), np.flatnonzero(bank_groups == group)
        if not len(cols):
            continue
        d = pose_distances(features[rows], bank.features[cols]).astype(np.float64)  # [R, C]
        d[np.abs(bank.frames[cols][None] - rows[:, None]) < gap] = np.inf
        order = np.argsort(d, axis=1)[:, :k]
        found = np.take_along_axis(d, order, axis=1)
        out[rows, : order.shape[1]] = np.where(np.isfinite(found), cols[order], -1)
    return out


def drive_choices(bank: ExemplarBank, joints: np.ndarray, stickiness: float = STICKINESS) -> np.ndarray:
    """[T] the bank frame of each driven pose (``joints`` [T, J, 2] canvas): the nearest, kept from one frame to
    the next until another is nearer by ``stickiness`` of the kept one's distance."""
    d = pose_distances(pose_features(joints), bank.features)  # [T, K]
    out = np.empty(len(joints), np.int64)
    keep = -1
    for t, row in enumerate(d):
        best = int(np.argmin(row))
        if keep < 0 or row[best] < (1.0 - stickiness) * row[keep]:
            keep = best
        out[t] = keep
    return out


__all__ = ["ExemplarBank", "choose_bank", "drive_choices", "fit_onto", "limb_mask", "pose_distances",
           "pose_features", "stray_limbs", "training_choices", "transform", "warp_onto"]
