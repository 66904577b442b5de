"""Images of a report: pose panels, overlays, captioned strips, still frames."""

from __future__ import annotations

import numpy as np
import pytest

from clone.report.panels import (
    caption_height,
    overlay,
    pose_panel,
    side_by_side,
    still_image,
    still_indices,
)
from tests.clone.report.helpers import SIZE, make_methods, walk


def test_side_by_side_and_still_indices():
    a = np.zeros((30, 40, 3), np.uint8)
    b = np.full((61, 61, 3), 255, np.uint8)
    out = side_by_side([a, b], ["a", "b"], 61)
    assert caption_height(61) == 22
    assert out.shape == (61 + 22 + 1, 81 + 61, 3)  # 40x30 -> 81x61 and 61x61, one row padded to even
    assert out.shape[0] % 2 == 0 and out.shape[1] % 2 == 0
    assert still_indices(100, 4) == [20, 40, 60, 80]
    assert still_indices(2, 4) == [0, 1] and still_indices(0) == []
    panel = pose_panel(walk(1).joints[0], "body15", (SIZE, SIZE * 2), 32)
    assert panel.shape == (32, 16, 3) and panel.any()


def test_overlay_and_still_image():
    frame = np.zeros((SIZE, SIZE, 3), np.uint8)
    drawn = overlay(frame[:, ::-1], walk(1).joints[0], "body15")  # a strided view, as generators give
    assert drawn.shape == frame.shape and drawn.any() and not frame.any()  # a copy, the frame untouched
    assert not overlay(frame, None, "body15").any()
    with pytest.raises(ValueError, match="panels for"):
        side_by_side([frame], ["a", "b"], 32)

    methods, info, gt = make_methods(frames=6, with_frames=False)
    t = still_indices(6, 3)[0]
    with_truth = still_image(t, methods, info, gt, 40)
    without = still_image(t, methods, info, None, 40)
    assert with_truth.shape[0] == 40 + caption_height(40) and with_truth.shape[1] == 4 * 40
    assert without.shape[1] == 3 * 40  # driver | global scaling | retargeted
    with pytest.raises(ValueError, match="past the driver"):
        still_image(6, methods, info, gt, 40)
