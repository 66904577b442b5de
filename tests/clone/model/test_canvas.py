import numpy as np
import pytest

from clone.model.canvas import (
    Canvas,
    canvas_to_image,
    choose_canvas,
    crop_canvas,
    cut_frame,
    full_frame_canvas,
    image_to_canvas,
    pose_thickness,
    render_pose_map,
)
from pose_io import BODY15, InputError


@pytest.mark.parametrize(
    "canvas",
    [
        Canvas(x0=37, y0=-5, side=91, size=64, image_size=(200, 120)),
        Canvas(x0=0, y0=0, side=64, size=128, image_size=(64, 64)),
        full_frame_canvas((480, 640), 128),
    ],
)
def test_image_canvas_round_trip(canvas):
    rng = np.random.default_rng(0)
    pts = rng.uniform(-50, 700, size=(7, 5, 2)).astype(np.float32)
    pts[0, 0] = np.nan
    back = canvas_to_image(image_to_canvas(pts, canvas), canvas)
    np.testing.assert_allclose(back, pts, atol=1e-3)
    assert np.isnan(back[0, 0]).all()


def test_mapping_known_values():
    canvas = Canvas(x0=10, y0=20, side=100, size=50, image_size=(300, 300))
    # Pixel-centre convention of cv2.resize: image pixel 10.5 +- 0.5 is canvas pixel 0.
    np.testing.assert_allclose(image_to_canvas(np.array([10.5, 20.5]), canvas), [0.0, 0.0], atol=1e-6)
    np.testing.assert_allclose(image_to_canvas(np.array([109.5, 119.5]), canvas), [49.5, 49.5], atol=1e-5)


def test_full_frame_letterbox_and_cut():
    canvas = full_frame_canvas((40, 20), 32)  # landscape: bars above and below
    assert (canvas.x0, canvas.y0, canvas.side) == (0, -10, 40)
    frame = np.full((20, 40, 3), 200, dtype=np.uint8)
    out = cut_frame(frame, canvas)
    assert out.shape == (32, 32, 3) and out.dtype == np.uint8
    assert out[:6].max() == 0 and out[-6:].max() == 0  # black bars
    assert out[12:20].min() == 200


def test_cut_frame_agrees_with_point_mapping():
    # A blob at a known image point appears where image_to_canvas says.
    h, w = 150, 220
    yy, xx = np.mgrid[0:h, 0:w]
    p = np.array([131.3, 77.8])
    blob = np.exp(-((xx - p[0]) ** 2 + (yy - p[1]) ** 2) / (2 * 6.0**2))
    frame = np.repeat((blob * 255).round().astype(np.uint8)[..., None], 3, axis=2)
    canvas = Canvas(x0=60, y0=-20, side=150, size=64, image_size=(w, h))
    out = cut_frame(frame, canvas)[..., 0].astype(np.float64)
    cy, cx = np.mgrid[0:64, 0:64]
    centroid = np.array([(out * cx).sum(), (out * cy).sum()]) / out.sum()
    np.testing.assert_allclose(centroid, image_to_canvas(p, canvas), atol=0.1)


def test_crop_canvas_contains_performer_with_margin():
    rng = np.random.default_rng(1)
    joints = np.stack([rng.uniform([300, 200], [360, 320], size=(15, 2)) for _ in range(30)]).astype(np.float32)
    joints[3, :5] = np.nan
    canvas = crop_canvas(joints, (1280, 720), 128, margin=0.25)
    assert canvas.mode == "crop"
    assert 120 < canvas.side < 720
    c = image_to_canvas(joints, canvas)
    ok = np.isfinite(c).all(-1)
    assert (c[ok] > 5).all() and (c[ok] < 123).all()
    assert 0 <= canvas.x0 and canvas.x0 + canvas.side <= 1280
    assert 0 <= canvas.y0 and canvas.y0 + canvas.side <= 720


def test_crop_canvas_shifted_inside_frame_and_full_when_too_big():
    joints = np.array([[[5.0, 50.0], [30.0, 95.0]]] * 3, dtype=np.float32)  # near the left edge
    canvas = crop_canvas(joints, (400, 100), 64, margin=0.1)
    assert canvas.mode == "crop" and canvas.x0 == 0 and canvas.y0 >= 0 and canvas.y0 + canvas.side <= 100
    big = np.array([[[0.0, 0.0], [399.0, 99.0]]], dtype=np.float32)
    assert crop_canvas(big, (400, 100), 64).mode == "full"
    assert choose_canvas(big, (400, 100), 64, mode="full") == full_frame_canvas((400, 100), 64)
    with pytest.raises(ValueError, match="valid: crop, full"):
        choose_canvas(big, (400, 100), 64, mode="zoom")
    with pytest.raises(InputError, match="no visible joints"):
        crop_canvas(np.full((4, 15, 2), np.nan, dtype=np.float32), (400, 100), 64)


def test_canvas_dict_round_trip_and_wrong_frame_size():
    canvas = Canvas(x0=-3, y0=4, side=77, size=32, image_size=(90, 60), mode="crop")
    assert Canvas.from_dict(canvas.to_dict()) == canvas
    with pytest.raises(InputError, match="90x60"):
        cut_frame(np.zeros((10, 10, 3), np.uint8), canvas)


def test_render_pose_map_draws_only_visible_joints():
    joints = np.full((15, 2), np.nan, dtype=np.float32)
    assert render_pose_map(joints, 64, BODY15).max() == 0
    joints[BODY15.index("neck")] = (32, 20)
    joints[BODY15.index("mid_hip")] = (32, 44)
    img = render_pose_map(joints, 64, BODY15)
    assert img.shape == (64, 64, 3) and img.dtype == np.uint8
    assert img[30, 32].max() > 0 and img[5, 5].max() == 0
    assert pose_thickness(128) == 2 and pose_thickness(32) == 1
