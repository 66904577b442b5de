"""Flat cartoon drawing of body15 poses: filled limbs with dark outlines, a round head with a face, one palette.

Every size comes from the character (its height and head radius in pixels), never from the pose of a frame,
so the figure keeps its build while it moves. Parts are drawn back to front (legs, trunk, arms, head), each
outlined on its own, so a limb in front of the trunk stays readable; the character's right side is a shade
darker than its left.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator
from dataclasses import dataclass, field

import cv2
import numpy as np

from pose_io.draw import blank_canvas
from pose_io.track import PoseTrack
from retarget.network.preprocess import LAYOUT

RGB = tuple[int, int, int]
_SHIFT = 4  # sub-pixel bits of OpenCV's drawing calls
_ONE = float(1 << _SHIFT)
_J = LAYOUT.index


@dataclass(frozen=True)
class Palette:
    """The character's colours (RGB) and the scene's."""

    skin: RGB = (250, 205, 160)
    hair: RGB = (90, 55, 35)
    shirt: RGB = (70, 140, 230)
    pants: RGB = (55, 60, 110)
    shoes: RGB = (60, 40, 35)
    outline: RGB = (30, 25, 35)
    eyes: RGB = (30, 25, 35)
    mouth: RGB = (180, 60, 70)
    background: RGB = (246, 240, 224)
    floor: RGB = (214, 204, 180)
    shadow: RGB = (186, 176, 152)
    right_shade: float = 0.85


@dataclass(frozen=True)
class CartoonLook:
    """Sizes of one character in pixels, and its colours.

    Attributes:
        height: the character's skeleton height.
        head_radius: radius of the head.
        head_offset: the head's centre is at ``neck + head_offset * (nose - neck)``.
        shoulder_width: shoulder-to-shoulder width seen from the front (tells which way the figure faces).
        ground_y: image row of the floor line.
        palette: colours.
        arm, leg, trunk, line: widths of arms, legs, the trunk and the outline, in heights.
    """

    height: float
    head_radius: float
    head_offset: float
    shoulder_width: float
    ground_y: float
    palette: Palette = field(default_factory=Palette)
    arm: float = 0.065
    leg: float = 0.09
    trunk: float = 0.17
    line: float = 0.012

    def px(self, share: float) -> int:
        """A width given in heights, in whole pixels (at least 1)."""
        return max(1, round(share * self.height))


def _pt(p: np.ndarray) -> tuple[int, int]:
    return round(float(p[0]) * _ONE), round(float(p[1]) * _ONE)


def _shade(color: RGB, factor: float) -> RGB:
    return tuple(round(c * factor) for c in color)  # type: ignore[return-value]


def _chain(canvas: np.ndarray, points: list[np.ndarray], colors: list[RGB], width: int, look: CartoonLook) -> None:
    """A limb of segments ``points[k] -> points[k + 1]`` in ``colors[k]``, outlined as one piece."""
    edge = width + 2 * look.px(look.line)
    for a, b in itertools.pairwise(points):
        cv2.line(canvas, _pt(a), _pt(b), look.palette.outline, edge, cv2.LINE_AA, _SHIFT)
    for a, b, color in zip(points, points[1:], colors):
        cv2.line(canvas, _pt(a), _pt(b), color, width, cv2.LINE_AA, _SHIFT)


def _blob(canvas: np.ndarray, centre: np.ndarray, radius: float, color: RGB, look: CartoonLook) -> None:
    """An outlined disc."""
    line = look.px(look.line)
    cv2.circle(canvas, _pt(centre), int((radius + line) * _ONE), look.palette.outline, -1, cv2.LINE_AA, _SHIFT)
    cv2.circle(canvas, _pt(centre), int(radius * _ONE), color, -1, cv2.LINE_AA, _SHIFT)


def _trunk(canvas: np.ndarray, p: np.ndarray, look: CartoonLook) -> None:
    """The pelvis, then a shoulders-hips polygon and a neck-root capsule (so a side view keeps a body) over it."""
    pal = look.palette
    _chain(canvas, [p[_J("r_hip")], p[_J("l_hip")]], [pal.pants], look.px(look.leg), look)
    quad = np.array([_pt(p[_J(n)]) for n in ("r_shoulder", "l_shoulder", "l_hip", "r_hip")], dtype=np.int32)
    spine = (_pt(p[_J("neck")]), _pt(p[_J("mid_hip")]))
    edge, trunk = 2 * look.px(look.line), look.px(look.trunk)
    for color, grow in ((pal.outline, edge), (pal.shirt, 0)):  # outline both shapes, then fill both
        cv2.fillPoly(canvas, [quad], color, cv2.LINE_AA, _SHIFT)
        if grow:
            cv2.polylines(canvas, [quad], True, color, grow, cv2.LINE_AA, _SHIFT)
        cv2.line(canvas, *spine, color, trunk + grow, cv2.LINE_AA, _SHIFT)


def _head(canvas: np.ndarray, p: np.ndarray, look: CartoonLook) -> None:
    """Neck, head, hair and a face that turns with the shoulders."""
    pal, r = look.palette, look.head_radius
    neck = p[_J("neck")]
    centre = neck + look.head_offset * (p[_J("nose")] - neck)
    _chain(canvas, [neck, neck + 0.8 * (centre - neck)], [pal.skin], look.px(0.05), look)
    # Facing: +1 = the front (the character's left shoulder on the image's right), -1 = the back.
    facing = float(np.clip((p[_J("l_shoulder"), 0] - p[_J("r_shoulder"), 0]) / max(look.shoulder_width, 1e-6), -1, 1))
    side = 1.0 if centre[0] >= neck[0] else -1.0
    _blob(canvas, centre, r, pal.hair if facing < -0.3 else pal.skin, look)
    cap = cv2.ellipse2Poly(_pt(centre), (int(r * _ONE), int(r * _ONE)), 0, 195, 345, 10)
    cv2.fillPoly(canvas, [cap], pal.hair, cv2.LINE_AA, _SHIFT)
    if facing < -0.3:
        return
    eye = max(1.0, 0.12 * r)
    turn = (1.0 - facing) * side  # 0 front-on, up to +-1.3 in profile
    eyes = (side * 0.45,) if facing < 0.3 else (-0.36 + 0.4 * turn, 0.36 + 0.4 * turn)
    for dx in eyes:
        cv2.circle(canvas, _pt(centre + [dx * r, 0.05 * r]), int(eye * _ONE), pal.eyes, -1, cv2.LINE_AA, _SHIFT)
    mouth = centre + [(0.5 * side if facing < 0.3 else 0.4 * turn) * r, 0.45 * r]
    axes = (int(0.28 * r * _ONE), int(0.15 * r * _ONE))
    cv2.ellipse(canvas, _pt(mouth), axes, 0, 10, 170, pal.mouth, max(1, look.px(0.008)), cv2.LINE_AA, _SHIFT)


def draw_cartoon(canvas: np.ndarray, joints: np.ndarray, look: CartoonLook) -> np.ndarray:
    """Draw one body15 pose onto ``canvas`` in place.

    Args:
        canvas: [H, W, 3] uint8 RGB image.
        joints: [15, 2] complete body15 pixel coordinates.
        look: the character's sizes and colours.

    Returns:
        ``canvas``.
    """
    p = np.clip(np.asarray(joints, dtype=np.float64), -4 * max(canvas.shape), 5 * max(canvas.shape))
    pal = look.palette
    feet = p[[_J("l_ankle"), _J("r_ankle")]]
    axes = (int(0.2 * look.height * _ONE), int(0.03 * look.height * _ONE))
    centre = _pt([feet[:, 0].mean(), look.ground_y])
    cv2.ellipse(canvas, centre, axes, 0, 0, 360, pal.shadow, -1, cv2.LINE_AA, _SHIFT)
    for side, shade in (("r", pal.right_shade), ("l", 1.0)):
        leg = [p[_J(f"{side}_{n}")] for n in ("hip", "knee", "ankle")]
        _chain(canvas, leg, [_shade(pal.pants, shade)] * 2, look.px(look.leg), look)
        _blob(canvas, leg[-1] + [0, 0.02 * look.height], 0.05 * look.height, _shade(pal.shoes, shade), look)
    _trunk(canvas, p, look)
    for side, shade in (("r", pal.right_shade), ("l", 1.0)):
        arm = [p[_J(f"{side}_{n}")] for n in ("shoulder", "elbow", "wrist")]
        _chain(canvas, arm, [_shade(pal.shirt, shade), _shade(pal.skin, shade)], look.px(look.arm), look)
        _blob(canvas, arm[-1], 0.04 * look.height, _shade(pal.skin, shade), look)
    _head(canvas, p, look)
    return canvas


def scene(size: tuple[int, int], look: CartoonLook) -> np.ndarray:
    """[H, W, 3] empty scene: a flat wall and the floor below the character's ground line."""
    w, h = size
    canvas = blank_canvas(w, h, look.palette.background)
    floor = round(look.ground_y + 0.03 * look.height)
    if floor < h:
        canvas[max(floor, 0) :] = look.palette.floor
    return canvas


def cartoon_frames(track: PoseTrack, look: CartoonLook) -> Iterator[np.ndarray]:
    """The character in every frame of a complete body15 ``track``, at ``track.image_size``.

    Yields:
        [H, W, 3] uint8 RGB frames.
    """
    background = scene(track.image_size, look)
    for joints in track.joints:
        yield draw_cartoon(background.copy(), joints, look)
