"""When an ankle touches the ground: the contact test of the foot-contact cleanup (:mod:`pose_io.feet`) and of the
report's foot-skating measure.

An ankle touches the ground in a frame when it is within ``height_tol * height`` of its
lowest point (largest y) over a centred window of about a second and moves slowly *vertically*
(``|dy| <= speed_tol * height``). Horizontal speed is deliberately not part of the test: the same test finds the
frames in which the report measures foot skating (``clone.metrics.poses.foot_slide``), and a speed cap there
would cap the very slide it measures.
"""

from __future__ import annotations

import numpy as np

from pose_io.layouts import JointLayout
from pose_io.measures import ANKLES, as_layout, check_joints

# The contact test's defaults (``foot_contacts``), shared by the cleanup and the report's foot-skating measure.
CONTACT_WINDOW = 31
CONTACT_HEIGHT_TOL = 0.02
CONTACT_SPEED_TOL = 0.01


def contact_window(fps: float) -> int:
    """Odd number of frames closest to one second: the window in which an ankle's lowest point is the ground."""
    return round(fps) // 2 * 2 + 1


def _window_max(values: np.ndarray, window: int) -> np.ndarray:
    """[T] NaN-ignoring maximum of ``values`` [T] over a centred window of ``window`` frames."""
    half = max(0, window // 2)
    padded = np.pad(values, half, constant_values=np.nan)
    windows = np.lib.stride_tricks.sliding_window_view(padded, 2 * half + 1)  # [T, 2 half + 1]
    out = np.full(values.shape, np.nan)
    seen = ~np.isnan(windows).all(axis=1)
    out[seen] = np.nanmax(windows[seen], axis=1)
    return out


def foot_contacts(
    joints: np.ndarray,
    height: float,
    layout: JointLayout | str = "body15",
    window: int = CONTACT_WINDOW,
    height_tol: float = CONTACT_HEIGHT_TOL,
    speed_tol: float = CONTACT_SPEED_TOL,
) -> np.ndarray:
    """Which ankles touch the ground in which frames.

    Args:
        joints: [T, J, 2] pixel coordinates (y down).
        height: body height in pixels; the tolerances are fractions of it.
        layout: joint layout of ``joints`` (needs ``l_ankle``, ``r_ankle``).
        window: frames of the centred window whose lowest ankle point is the ground (about a second).
        height_tol: how far above that point (in heights) an ankle may be and still touch.
        speed_tol: the largest vertical move (heights per frame) of an ankle that touches.

    Returns:
        [T, 2] bool, columns in ``ANKLES`` order.
    """
    layout = as_layout(layout)
    feet = check_joints(joints, layout, "foot contacts")[:, layout.indices(ANKLES)]  # [T, 2, 2]
    y = feet[..., 1]  # [T, 2]
    contact = np.zeros(y.shape, dtype=bool)
    for f in range(y.shape[1]):
        ground = _window_max(y[:, f], window)
        dy = np.abs(np.diff(y[:, f]))
        speed = np.concatenate([dy[:1], dy]) if dy.size else np.zeros(1)  # frame 0 uses the next step
        with np.errstate(invalid="ignore"):
            contact[:, f] = (y[:, f] >= ground - height_tol * height) & (speed <= speed_tol * height)
    return contact
