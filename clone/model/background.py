"""A background plate from a static-camera video: per pixel, the median over frames where the person is elsewhere.

The person's region in a frame is estimated from its pose: every limb drawn as a thick line, every joint
as a disc and the trunk filled, all ``margin`` times the performer's skeleton height wide (joints stop at the
wrists, ankles and nose; hands, feet, hair and clothes do not), joined by the person's own segmented silhouette
(MediaPipe's selfie segmentation, when installed), which reaches the hair, the dress and the hands. A pixel's plate value is the median over the
frames where it lies outside that region; a pixel the person covers in every frame is filled in from the free
pixels around it (OpenCV's Telea inpainting; its share is reported: there the plate is only a guess). The median
of all frames there, the earlier fallback, is the person herself, who then shows through as a ghost wherever the
driven pose leaves the spot.

Memory stays bounded whatever the video's length: at most ``max_frames`` evenly spaced frames are used, and the
median is taken a band of rows at a time. Frames are ``[T, H, W, 3]`` uint8 RGB (an array or a memory map);
joints ``[T, J, 2]`` in the same pixels, NaN where missing.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import cv2
import numpy as np

from pose_io.errors import InputError
from pose_io.layouts import JointLayout
from pose_io.measures import skeleton_height

log = logging.getLogger(__name__)

# Filled as one polygon when the layout has them: limbs alone leave the corners of the trunk uncovered.
TRUNK = ("neck", "r_shoulder", "r_hip", "mid_hip", "l_hip", "l_shoulder")
# Bytes of one band of the median's working array (uint16 values of the chosen frames).
_BAND_BYTES = 32 << 20
# Sorts after every uint8 value: marks a pixel of a frame where the person is.
_TAKEN = 256


@dataclass(frozen=True)
class PlateConfig:
    """How a plate is estimated.

    Attributes:
        max_frames: frames used at most (evenly spaced over the video).
        margin: half-width of the person's region around its skeleton, as a fraction of its skeleton height.
        segment: add the person's own silhouette (:mod:`pose_io.segment`, MediaPipe's selfie segmentation) to
            that region: hair, a dress and hands the pose does not reach; without MediaPipe, the pose alone.
        segment_margin: the silhouette grown by this fraction of the frame's larger side (its edge is soft).
    """

    max_frames: int = 150
    margin: float = 0.15
    segment: bool = True
    segment_margin: float = 0.02

    def __post_init__(self) -> None:
        if self.max_frames < 1:
            raise ValueError(f"PlateConfig.max_frames must be >= 1, got {self.max_frames}")
        if not self.margin >= 0:
            raise ValueError(f"PlateConfig.margin must be >= 0, got {self.margin}")


@dataclass(frozen=True, eq=False)
class Plate:
    """An estimated background plate.

    Attributes:
        image: [H, W, 3] uint8 RGB.
        free_frames: [H, W] int, frames in which each pixel was free of the person (0: a fallback pixel).
        frames: frames used.
        fallback_share: share of pixels the person covered in every frame used (inpainted from around them).
    """

    image: np.ndarray
    free_frames: np.ndarray
    frames: int
    fallback_share: float


def sample_frames(count: int, max_frames: int) -> np.ndarray:
    """[N] indices of at most ``max_frames`` evenly spaced frames out of ``count`` (first and last included)."""
    if count < 1:
        raise ValueError(f"no frames to sample from ({count})")
    return np.unique(np.linspace(0, count - 1, num=min(count, max_frames)).round().astype(np.int64))


def person_mask(joints: np.ndarray, shape: tuple[int, int], layout: JointLayout, radius: float) -> np.ndarray:
    """Where the person may be in one frame: limbs as thick lines, discs at the joints, the trunk filled.

    Args:
        joints: [J, 2] pixel coordinates, NaN where missing.
        shape: (height, width) of the frame.
        layout: the joints' layout.
        radius: half-width of the region around the skeleton, pixels.

    Returns:
        [H, W] bool, True where the person may be (all False when no joint is visible).
    """
    h, w = shape
    mask = np.zeros((h, w), dtype=np.uint8)
    ok = np.isfinite(joints).all(axis=-1)
    # Far-away points clamped so OpenCV's integer maths does not overflow; clipping does the rest.
    pts = np.round(np.clip(np.nan_to_num(joints), -4 * max(h, w), 5 * max(h, w))).astype(np.int32)
    r = max(1, int(np.ceil(radius)))
    for a, b in layout.limb_indices:
        if ok[a] and ok[b]:
            cv2.line(mask, tuple(pts[a]), tuple(pts[b]), 1, 2 * r + 1)
    for j in np.flatnonzero(ok):
        cv2.circle(mask, tuple(pts[j]), r, 1, -1)
    trunk = [layout.index(n) for n in TRUNK if layout.has(n)]
    trunk = [j for j in trunk if ok[j]]
    if len(trunk) >= 3:
        cv2.fillConvexPoly(mask, cv2.convexHull(pts[trunk]), 1)
    return mask.astype(bool)


def _silhouettes(frames: np.ndarray, picks: np.ndarray, margin: float) -> np.ndarray | None:
    """[N, H, W] bool: the person's segmented silhouette in the picked frames, grown by ``margin`` of the larger
    side; None without MediaPipe (the pose alone then says where the person is)."""
    from pose_io.segment import person_masks, segmentation_available

    if not segmentation_available():
        log.info("background plate: MediaPipe is not installed; the person's region comes from the pose alone")
        return None
    masks = person_masks(np.asarray(frames[i]) for i in picks)
    r = max(1, round(margin * max(masks.shape[1:])))
    kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1))
    return np.stack([cv2.dilate(m.astype(np.uint8), kernel).astype(bool) for m in masks])


def _median_band(values: np.ndarray, free: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-pixel median over the free frames of one band of rows.

    Args:
        values: [N, R, W, 3] uint8.
        free: [N, R, W] bool.

    Returns:
        ``(median [R, W, 3] uint8, free count [R, W] int)``; the median of a pixel free in no frame is that
        over all frames.
    """
    n = values.shape[0]
    v = values.astype(np.uint16)
    v[~free] = _TAKEN
    v.sort(axis=0)  # taken frames last
    count = free.sum(axis=0)  # [R, W]
    k = np.where(count > 0, count, n)[None, ..., None]  # [1, R, W, 1]
    if (count == 0).any():
        everything = np.sort(values, axis=0).astype(np.uint16)  # [N, R, W, 3]
        v = np.where((count == 0)[None, ..., None], everything, v)
    lower = np.take_along_axis(v, (k - 1) // 2, axis=0)[0]  # [R, W, 3]
    upper = np.take_along_axis(v, k // 2, axis=0)[0]
    return ((lower + upper + 1) // 2).astype(np.uint8), count


def estimate_plate(
    frames: np.ndarray, joints: np.ndarray, layout: JointLayout, usable: np.ndarray | None = None,
    config: PlateConfig = PlateConfig(),
) -> Plate:
    """The background plate of a static-camera video (see the module docstring).

    Args:
        frames: [T, H, W, 3] uint8 RGB (an array or a memory map; only the chosen frames are read).
        joints: [T, J, 2] pixel coordinates in ``frames``, NaN where missing.
        layout: the joints' layout.
        usable: [T] bool, frames whose pose is complete enough to say where the person is not (default:
            frames with any visible joint). The others only count for the fallback.
        config: frames used and the person's margin.

    Returns:
        The plate.

    Raises:
        InputError: no frames, frames and joints of different lengths, or no usable pose.
    """
    t, h, w = frames.shape[:3]
    if t == 0:
        raise InputError("background plate: no frames")
    if len(joints) != t:
        raise InputError(f"background plate: {t} frames but {len(joints)} poses")
    visible = np.isfinite(joints).all(axis=-1)  # [T, J]
    usable = visible.any(axis=1) if usable is None else np.asarray(usable, dtype=bool) & visible.any(axis=1)
    if not usable.any():
        raise InputError("background plate: no frame has a visible joint")
    try:
        height = skeleton_height(joints[usable], layout)
    except InputError:
        # Bones for the skeleton height are missing: the joints' box is the next best measure.
        pts = joints[usable][visible[usable]]
        height = float(np.ptp(pts[:, 1])) if len(pts) else 0.0
    radius = config.margin * max(height, 1.0)
    picks = sample_frames(t, config.max_frames)  # [N]
    free = np.stack([~person_mask(joints[i], (h, w), layout, radius) if usable[i] else np.zeros((h, w), bool)
                     for i in picks])  # [N, H, W]
    if config.segment:
        silhouettes = _silhouettes(frames, picks, config.segment_margin)
        if silhouettes is not None:
            free &= ~silhouettes
    image = np.empty((h, w, 3), dtype=np.uint8)
    count = np.empty((h, w), dtype=np.int64)
    rows = max(1, _BAND_BYTES // max(1, len(picks) * w * 3 * 2))
    for r0 in range(0, h, rows):
        band = np.asarray(frames[picks, r0:r0 + rows])  # [N, R, W, 3]
        image[r0:r0 + rows], count[r0:r0 + rows] = _median_band(band, free[:, r0:r0 + rows])
    never = count == 0
    if never.any() and not never.all():
        # The median of all frames there is the person herself, who would then show through the generator's
        # alpha as a ghost wherever the driven pose leaves that spot: fill it from the free pixels around it.
        radius = max(3, round(0.02 * max(h, w)))
        image = cv2.inpaint(image, never.astype(np.uint8), radius, cv2.INPAINT_TELEA)
    share = float(never.mean())
    log.debug("background plate from %d frames (person margin %.1f px); %.1f%% of pixels never free",
             len(picks), radius, 100.0 * share)
    return Plate(image=image, free_frames=count, frames=len(picks), fallback_share=share)
