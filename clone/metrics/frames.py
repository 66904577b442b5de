"""Measures of generated frames against the true ones: SSIM and PSNR of the whole frame, of the person and of
the background; and of a video on its own: flicker in the person's box (:class:`FlickerMeter`).

Frames are [H, W, 3] uint8 RGB. The person crop is the box of the ground-truth pose plus a margin, so a method
that puts the person in the wrong place or with the wrong shape scores low there even on a perfect background.
The background is every pixel outside that box: where the true frame shows only the scene, so its PSNR says how
well the generator reproduces the reference's background, whatever the person does. Identical frames have
PSNR = inf.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from clone.metrics.table import Scores, nan_mean
from pose_io.errors import InputError


def person_box(
    joints: np.ndarray, image_size: tuple[int, int], margin: float = 0.15, min_size: int = 7
) -> tuple[int, int, int, int] | None:
    """Box around one pose, for a crop.

    Args:
        joints: [J, 2] pixel coordinates, NaN where missing.
        image_size: (width, height) of the image.
        margin: added on every side, as a fraction of the larger side of the joints' box (joints stop at the
            ankles and nose, the person does not).
        min_size: smallest side of the box (SSIM needs 7 pixels), if the image allows.

    Returns:
        (x0, y0, x1, y1) integer pixel box inside the image (x1, y1 exclusive), or None if no joint is present.
    """
    joints = np.asarray(joints, dtype=np.float64)
    ok = ~np.isnan(joints).any(axis=-1)
    if not ok.any():
        return None
    w, h = image_size
    lo, hi = joints[ok].min(axis=0), joints[ok].max(axis=0)
    pad = margin * float((hi - lo).max())
    box = []
    for axis, limit in ((0, w), (1, h)):
        a, b = lo[axis] - pad, hi[axis] + pad
        grow = max(0.0, min(min_size, limit) - (b - a)) / 2
        a, b = int(np.floor(max(0.0, a - grow))), int(np.ceil(min(float(limit), b + grow)))
        if b - a < min(min_size, limit):  # pushed against an edge: extend the other way
            a, b = (0, min(min_size, limit)) if a == 0 else (limit - min(min_size, limit), limit)
        box.append((a, b))
    (x0, x1), (y0, y1) = box
    return x0, y0, x1, y1


def frame_pair_scores(pred: np.ndarray, gt: np.ndarray) -> tuple[float, float]:
    """SSIM and PSNR (dB) of one generated frame against the true one.

    Args:
        pred: [H, W, 3] uint8 RGB generated frame.
        gt: [H, W, 3] uint8 RGB ground truth of the same size (at least 7 x 7).

    Returns:
        (ssim, psnr); psnr is inf for identical frames.
    """
    from skimage.metrics import peak_signal_noise_ratio, structural_similarity

    if pred.shape != gt.shape:
        raise InputError(f"ground-truth frame: size {gt.shape} does not match the generated {pred.shape}")
    ssim = structural_similarity(pred, gt, channel_axis=-1, data_range=255)
    with np.errstate(divide="ignore"):  # identical frames: MSE 0, PSNR inf
        psnr = peak_signal_noise_ratio(gt, pred, data_range=255)
    return float(ssim), float(psnr)


def _psnr(mse: np.ndarray) -> np.ndarray:
    """PSNR in dB of 8-bit images from their mean squared error (inf where it is 0)."""
    with np.errstate(divide="ignore"):
        return 10.0 * np.log10(255.0**2 / mse)


def background_error(pred: np.ndarray, gt: np.ndarray, box: tuple[int, int, int, int]) -> tuple[float, int]:
    """Summed squared error and number of values of two frames outside ``box`` (the person's).

    Args:
        pred, gt: [H, W, 3] uint8 RGB frames of the same size.
        box: (x0, y0, x1, y1) from :func:`person_box`.

    Returns:
        ``(sse, count)``; count is 0 when the box covers the whole frame.
    """
    x0, y0, x1, y1 = box
    outside = np.ones(gt.shape[:2], dtype=bool)
    outside[y0:y1, x0:x1] = False
    diff = pred[outside].astype(np.float64) - gt[outside].astype(np.float64)  # [N, 3]
    return float((diff**2).sum()), int(diff.size)


class FrameScorer:
    """Collects SSIM/PSNR of generated frames against the truth, one frame at a time.

    Frames arrive one by one from a generator, so a whole video never has to sit in memory.
    """

    def __init__(self, gt_joints: np.ndarray | None = None, margin: float = 0.15) -> None:
        """Args:
        gt_joints: [T, J, 2] ground-truth poses for the person crop, or None for whole frames only.
        margin: crop margin (see ``person_box``).
        """
        self.gt_joints = gt_joints
        self.margin = margin
        self._rows: list[tuple[float, float, float, float]] = []
        self._background: list[tuple[float, int]] = []  # (summed squared error, pixel values) outside the box

    def add(self, pred: np.ndarray, gt: np.ndarray) -> None:
        """Score the next frame pair ([H, W, 3] uint8 RGB each)."""
        t = len(self._rows)
        if self.gt_joints is not None and t >= len(self.gt_joints):
            raise InputError(
                f"ground-truth poses: only {len(self.gt_joints)} frames, more video frames given"
            )
        ssim, psnr = frame_pair_scores(pred, gt)
        crop = (float("nan"), float("nan"))
        if self.gt_joints is not None:
            box = person_box(self.gt_joints[t], (gt.shape[1], gt.shape[0]), self.margin)
            if box is not None:
                x0, y0, x1, y1 = box
                crop = frame_pair_scores(pred[y0:y1, x0:x1], gt[y0:y1, x0:x1])
                self._background.append(background_error(pred, gt, box))
        self._rows.append((ssim, psnr, *crop))

    def scores(self) -> Scores:
        """``ssim``, ``psnr`` (and ``ssim_crop``, ``psnr_crop``, ``psnr_background`` with ground-truth poses):
        per frame and mean; the background's summary is the PSNR of the squared error pooled over all frames
        (a mean of per-frame values would be inf as soon as one frame's background is exact)."""
        names = ("ssim", "psnr", "ssim_crop", "psnr_crop")[: 4 if self.gt_joints is not None else 2]
        table = np.array(self._rows, dtype=np.float64).reshape(-1, 4)
        per_frame = {n: table[:, i] for i, n in enumerate(names)}
        summary = {n: nan_mean(v) for n, v in per_frame.items()}
        if self._background:
            sse, count = np.array(self._background, dtype=np.float64).T  # [F] each
            per_frame["psnr_background"] = _psnr(sse / np.maximum(count, 1))
            summary["psnr_background"] = float(_psnr(np.array(sse.sum() / max(count.sum(), 1))))
        return Scores(per_frame, summary)


def frame_scores(
    pred_frames: Sequence[np.ndarray], gt_frames: Sequence[np.ndarray], gt_joints: np.ndarray | None = None
) -> Scores:
    """SSIM/PSNR of a generated video against the true one (see ``FrameScorer``).

    Args:
        pred_frames: T frames [H, W, 3] uint8 RGB (or a [T, H, W, 3] array).
        gt_frames: T frames of the same size.
        gt_joints: [T, J, 2] ground-truth poses for the person crop, or None.
    """
    scorer = FrameScorer(gt_joints)
    if len(pred_frames) != len(gt_frames):
        raise InputError(
            f"ground-truth frames: {len(gt_frames)} frames, generated video has {len(pred_frames)}"
        )
    if gt_joints is not None and len(gt_joints) != len(pred_frames):
        raise InputError(f"ground-truth poses: {len(gt_joints)} frames, video has {len(pred_frames)}")
    for pred, gt in zip(pred_frames, gt_frames):
        scorer.add(pred, gt)
    return scorer.scores()


class FlickerMeter:
    """Flicker of a video in the person's box, one frame at a time: the mean absolute change (8-bit levels)
    between each frame and the one before, inside the box of the later frame's pose. A still person on a
    still background gives 0; compare a generated video's with the real one's."""

    def __init__(self, margin: float = 0.15) -> None:
        self.margin = margin
        self._prev: np.ndarray | None = None
        self._changes: list[float] = []

    def add(self, frame: np.ndarray, joints: np.ndarray | None) -> None:
        """The next frame ([H, W, 3] uint8 RGB) and its [J, 2] pose in its pixels (None or all NaN: not measured)."""
        prev, self._prev = self._prev, frame
        box = None if prev is None or joints is None else person_box(joints, (frame.shape[1], frame.shape[0]),
                                                                     self.margin)
        if box is None or prev.shape != frame.shape:
            self._changes.append(float("nan"))
            return
        x0, y0, x1, y1 = box
        a, b = prev[y0:y1, x0:x1].astype(np.float32), frame[y0:y1, x0:x1].astype(np.float32)
        self._changes.append(float(np.abs(a - b).mean()))

    def per_frame(self) -> np.ndarray:
        """[T] the change into each frame (NaN for the first and where no box was given)."""
        return np.array(self._changes, dtype=np.float64)

    def value(self) -> float:
        """The mean change over the frames measured (NaN for none)."""
        return nan_mean(self.per_frame())
