"""What a pose track may claim, checked before anything is allocated, drawn or scaled.

Every size here is one a file or an option can claim, and memory and disk are shared, so each is checked
where it enters (readers, ``--size``, sidecars, :class:`pose_io.track.PoseTrack`, resampling, video) and
ends as an :class:`InputError` naming where it came from:

- image sides: 1 to :data:`MAX_IMAGE_SIDE` (16,384) pixels; a 16,384² RGB frame is 768 MiB already.
- frame rates: :data:`MIN_FPS` (0.01) to :data:`MAX_FPS` (1,000) frames per second.
- track length: at most :data:`MAX_FRAMES` (1,000,000; over 9 hours at 30 fps), also after resampling.
- coordinates: real numbers (no complex, object or text arrays), finite, within float32 range (beyond
  it they would silently become infinite), and at most :data:`TRACK_RANGE` (16) image sizes outside the
  image (an image size is the longer side): nothing a camera saw lies further out, and coordinates that
  do are in another unit or belong to another image size.

Outlier joints. A detector sometimes puts one joint absurdly far away (a wrist at x = 10⁶). Such a joint
would stretch the inferred image, the tracking gate, body heights and the retargeted body, so
:func:`outlier_mask` flags it and readers (and the retargeting input) drop it as missing, with one warning
counting the dropped joints. A visible joint is an outlier when BOTH

1. it lies more than :data:`OUTLIER_IMAGE_MARGIN` (1) image size outside the image: beyond
   ``[-S, W + S] x [-S, H + S]`` with ``S = max(W, H)``. When the image size is unknown (to be inferred
   from the data) the "image" is the bounding box of the joints that are not far from their body; and
2. it lies more than :data:`OUTLIER_BODY_SIZES` (4) body sizes from its pose's median joint (per-axis
   median of the pose's visible joints). The body size is :data:`BODY_PER_SPREAD` (3) times the median,
   over all poses of the source with at least :data:`MIN_BODY_JOINTS` (3) visible joints, of a pose's
   median joint distance from its median joint; for a standing person that is about their height.
   A pose with fewer visible joints has no body to judge by: rule 1 alone decides.

So a foot a little below the frame is kept (rule 1 fails), and so is a whole person standing beside the
frame (rule 2 fails); that a joint is both far from the image and far from its body is what makes it
impossible. When most joints of a pose are far away its median is too and nothing is dropped; the
coordinate range above or the image-size limit then reject the track instead.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np

from pose_io.errors import InputError

MAX_IMAGE_SIDE = 16_384
MIN_FPS = 0.01
MAX_FPS = 1_000.0
MAX_FRAMES = 1_000_000
FLOAT32_MAX = float(np.finfo(np.float32).max)
TRACK_RANGE = 16.0
OUTLIER_IMAGE_MARGIN = 1.0
OUTLIER_BODY_SIZES = 4.0
BODY_PER_SPREAD = 3.0
MIN_BODY_JOINTS = 3


def check_image_size(size: object, what: str) -> tuple[int, int]:
    """``size`` as (width, height) ints; InputError naming ``what`` unless two whole numbers in 1..16,384.

    Args:
        size: a (width, height) pair of numbers.
        what: how the message names the value, e.g. ``"image size"`` or ``"<file>: image_size"``.
    """
    try:
        w, h = size  # type: ignore[misc]
    except (TypeError, ValueError):
        raise InputError(f"{what} must be (width, height), got {_short_repr(size)}") from None
    sides = []
    for v in (w, h):
        if isinstance(v, bool) or not isinstance(v, numbers.Real):
            raise InputError(f"{what} must be two whole numbers, got {_short_repr(size)}")
        try:
            ok = math.isfinite(float(v)) and v == math.floor(v) and 1 <= v <= MAX_IMAGE_SIDE
        except OverflowError:  # an int beyond float range
            ok = False
        if not ok:
            raise InputError(
                f"{what} {_side(w)}x{_side(h)}: each side must be a whole number from 1 to {MAX_IMAGE_SIDE} pixels"
            )
        sides.append(int(v))
    return sides[0], sides[1]


def check_fps(fps: object, what: str) -> float:
    """``fps`` as a float; InputError naming ``what`` (e.g. ``"--fps"``) unless a number from 0.01 to 1,000."""
    if isinstance(fps, (str, bytes)):
        raise InputError(f"{what} must be a number of frames per second, got {_short_repr(fps)}")
    try:
        value = float(fps)  # type: ignore[arg-type]
    except OverflowError:  # an int beyond float range
        value = math.inf
    except (TypeError, ValueError):
        raise InputError(f"{what} must be a number of frames per second, got {_short_repr(fps)}") from None
    if not (math.isfinite(value) and MIN_FPS <= value <= MAX_FPS):
        raise InputError(f"{what} {_side(fps)}: must be from {MIN_FPS:g} to {MAX_FPS:g} frames per second")
    return value


def check_frame_count(count: int, what: str) -> int:
    """``count`` itself; InputError naming ``what`` when it exceeds :data:`MAX_FRAMES`."""
    if count > MAX_FRAMES:
        raise InputError(f"{what}: {count:,} frames; at most {MAX_FRAMES:,} are allowed")
    return count


def real_array(values: object, what: str) -> np.ndarray:
    """``values`` as an array of real numbers, unchanged in dtype; InputError naming ``what`` otherwise.

    Rejects complex (its imaginary part would be dropped), object, text and boolean arrays, infinite
    values and values beyond float32 range (they would turn infinite when stored as float32). NaN is
    allowed: it marks a missing joint.
    """
    arr = values if isinstance(values, np.ndarray) else _as_array(values, what)
    if arr.dtype.kind not in "iuf":
        raise InputError(f"{what}: must hold real numbers, got dtype {arr.dtype}")
    if arr.dtype.kind == "f" and arr.size:
        magnitude = _magnitude(arr)
        if math.isinf(magnitude):
            raise InputError(f"{what}: has infinite values")
        if magnitude > FLOAT32_MAX:
            raise InputError(f"{what}: value {magnitude:.3g} is beyond float32 range (±{FLOAT32_MAX:.3g})")
    return arr


def check_coordinate_range(joints: np.ndarray, image_size: tuple[int, int], what: str,
                           names: tuple[str, ...] = ()) -> None:
    """InputError when a visible joint of [T, J, 2] ``joints`` lies more than TRACK_RANGE image sizes out."""
    w, h = image_size
    reach = TRACK_RANGE * max(w, h)
    if _within(joints, -reach, min(w, h) + reach):  # the common case, two reductions and no temporaries
        return
    with np.errstate(invalid="ignore"):
        far = ((joints < -reach) | (joints > np.array([w, h]) + reach)).any(axis=-1)  # [T, J], NaN -> False
    if far.any():
        t, j = (int(v) for v in np.argwhere(far)[0])
        name = names[j] if j < len(names) else f"joint {j}"
        x, y = (float(v) for v in joints[t, j])
        raise InputError(
            f"{what}: {name} at frame {t} lies at ({x:.6g}, {y:.6g}), more than {TRACK_RANGE:g} image sizes "
            f"outside the {w}x{h} image ({int(far.sum())} such joints); wrong image size, or not pixels?"
        )


def outlier_mask(xy: np.ndarray, image_size: tuple[int, int] | None) -> np.ndarray:
    """Which joints of a set of poses are outliers (rules in the module docstring).

    Linear in the number of joints. With a known image size, a source without any coordinate beyond rule
    1's bounds (nearly every one) is settled by a NaN-ignoring min and max; otherwise x and y are worked on
    as [N, J] planes (numpy reduces short axes slowly) and the medians come from partitions.

    Args:
        xy: [N, J, 2] pixel coordinates of N poses (any frames, any people of one source), NaN where missing.
        image_size: (width, height) of the image, or None when it is unknown (to be inferred).

    Returns:
        [N, J] bool, True for the outliers (never for a missing joint).
    """
    values = xy if isinstance(xy, np.ndarray) and xy.dtype.kind == "f" else np.asarray(xy, dtype=np.float64)
    if image_size is not None:
        size = np.array(image_size, dtype=np.float64)
        margin = OUTLIER_IMAGE_MARGIN * max(float(size.max()), 1.0)
        # Rule 1 needs a coordinate beyond [-margin, size + margin]: none beyond the narrower [-margin,
        # min(size) + margin] means no outlier (float32 -> float64 is exact, so the bounds compare alike).
        if _within(values, -margin, float(size.min()) + margin):
            return np.zeros(values.shape[:2], dtype=bool)
    xy = np.asarray(values, dtype=np.float64)
    x, y = np.ascontiguousarray(xy[..., 0]), np.ascontiguousarray(xy[..., 1])  # [N, J] each
    visible = ~(np.isnan(x) | np.isnan(y))  # [N, J]
    out = np.zeros(visible.shape, dtype=bool)
    if not visible.any():
        return out
    dx, dy = x - _row_nanmedian(x)[:, None], y - _row_nanmedian(y)[:, None]  # from the pose's median joint
    dist = np.sqrt(dx * dx + dy * dy)  # [N, J] np.linalg.norm's sum to the bit; NaN where missing
    spread = _row_nanmedian(dist)  # [N], NaN for a pose without visible joints
    judged = np.count_nonzero(visible, axis=1) >= MIN_BODY_JOINTS  # [N]
    body = BODY_PER_SPREAD * float(np.median(spread[judged])) if judged.any() else 0.0
    with np.errstate(invalid="ignore"):
        near_body = judged[:, None] & (dist <= OUTLIER_BODY_SIZES * max(body, 1.0))  # [N, J]
    if image_size is not None:
        lo, hi = np.zeros(2), np.array(image_size, dtype=np.float64)
    else:
        anchor = visible & near_body
        if not anchor.any():
            return out  # nothing to measure the image by; the inferred size's limit decides
        lo, hi = np.array([x[anchor].min(), y[anchor].min()]), np.array([x[anchor].max(), y[anchor].max()])
    margin = OUTLIER_IMAGE_MARGIN * max(float((hi - lo).max()), 1.0)
    low, high = lo - margin, hi + margin  # [2]
    with np.errstate(invalid="ignore"):
        far_image = (x < low[0]) | (x > high[0]) | (y < low[1]) | (y > high[1])  # [N, J]
    return visible & far_image & ~near_body


def _within(values: np.ndarray, lo: float, hi: float) -> bool:
    """Whether every non-NaN value lies in [lo, hi] (True when all are NaN); NaN-ignoring min and max."""
    if not values.size:
        return True
    smallest, largest = float(np.fmin.reduce(values, axis=None)), float(np.fmax.reduce(values, axis=None))
    if math.isnan(smallest):  # every value NaN
        return True
    return lo <= smallest and largest <= hi


def _magnitude(values: np.ndarray) -> float:
    """Largest absolute value of a float array ignoring NaN (0 when all are NaN), without an ``abs`` copy."""
    smallest, largest = float(np.fmin.reduce(values, axis=None)), float(np.fmax.reduce(values, axis=None))
    return 0.0 if math.isnan(largest) else max(abs(smallest), abs(largest))


def _row_nanmedian(a: np.ndarray) -> np.ndarray:
    """Median of each row of [N, J] ignoring NaN -> [N]; NaN where a row has no value.

    ``np.nanmedian`` over a short axis goes through masked arrays and is ~20x slower on long tracks; a sort is
    more than a median needs. Rows are grouped by their count ``c`` of values (usually one or two groups);
    a partition at ``c // 2`` (NaN goes last, as in a sort) puts the upper middle value there and only
    smaller ones before it, so the lower middle of an even count is their maximum: the same two values, and
    the same ``0.5 * (lo + hi)``, as a full sort gives.
    """
    a = np.ascontiguousarray(a, dtype=np.float64)
    count = a.shape[1] - np.count_nonzero(np.isnan(a), axis=1)  # [N]
    out = np.full(len(a), np.nan)
    for c in np.flatnonzero(np.bincount(count, minlength=a.shape[1] + 1)[1:]).tolist():
        c += 1
        rows = count == c
        every = bool(rows.all())
        hi = c // 2
        part = np.partition(a if every else a[rows], hi, axis=1)  # [n, J]
        upper = part[:, hi]
        lower = upper if c % 2 else part[:, :hi].max(axis=1)
        median = 0.5 * (lower + upper)
        if every:
            return median
        out[rows] = median
    return out


@dataclass(frozen=True)
class Dropped:
    """Outliers dropped from a source: how many, and the first one (frame, joint name, x, y) for the message."""

    count: int
    frame: int = -1
    joint: str = ""
    x: float = math.nan
    y: float = math.nan

    def message(self, source: str) -> str:
        """One line for the warning."""
        return (
            f"{source}: dropped {self.count} outlier joint{'s' if self.count != 1 else ''} as missing (each more "
            f"than {OUTLIER_IMAGE_MARGIN:g} image size outside the image and {OUTLIER_BODY_SIZES:g} body sizes "
            f"from its body), first {self.joint} at frame {self.frame}: ({self.x:.6g}, {self.y:.6g})"
        )


def _as_array(values: object, what: str) -> np.ndarray:
    try:
        return np.asarray(values)  # no cast: a complex list stays complex and is refused by dtype
    except (TypeError, ValueError, OverflowError):
        raise InputError(f"{what}: must be an array of real numbers") from None


def _side(v: object) -> str:
    try:
        return f"{float(v):.6g}"  # type: ignore[arg-type]
    except OverflowError:
        return ">1e308"
    except (TypeError, ValueError):
        return "?"


def _short_repr(value: object) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."
