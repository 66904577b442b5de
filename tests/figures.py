"""Pose tracks the tests build themselves: a walking figure with chosen proportions, no files needed.

The figure is drawn from bone lengths and joint angles (2D forward kinematics), so its limb lengths are
known exactly and two figures can differ in size and in proportions: the data retargeting tests need when
the authors' OpenPose examples (../shared) are not there.
"""

from __future__ import annotations

import numpy as np

from pose_io import BODY25, PoseTrack

J = BODY25.index


def walking_figure(
    frames: int = 96,
    *,
    height: float = 300.0,
    legs: float = 0.5,
    arms: float = 0.38,
    shoulders: float = 0.2,
    feet_y: float = 620.0,
    root_x: float = 360.0,
    drift: float = 60.0,
    period: float = 32.0,
    phase: float = 0.0,
    image_size: tuple[int, int] = (720, 720),
    fps: float = 30.0,
    dropped: float = 0.0,
    always_seen: tuple[str, ...] = (),
    seed: int = 0,
) -> PoseTrack:
    """A body25 person walking (seen from the side, three-quarter turned), arms and legs swinging.

    Args:
        frames: track length.
        height: standing height in pixels as :func:`pose_io.measures.skeleton_height` measures it
            (nose-neck + neck-mid_hip + hip-knee + knee-ankle).
        legs: hip-to-ankle length as a share of ``height``.
        arms: shoulder-to-wrist length as a share of ``height``.
        shoulders: shoulder width as a share of ``height``.
        feet_y: image row of the ankles when the legs are straight.
        root_x: image column of the mid hip at the start.
        drift: pixels the figure moves to the right over the track.
        period: frames per stride.
        phase: start of the stride, in frames.
        image_size: (width, height) of the frame.
        fps: frame rate.
        dropped: share of joints missing at random (NaN, confidence 0), the way a detector loses them.
        always_seen: joints never dropped.
        seed: seed of the dropped joints and of a small detection noise.

    Returns:
        The track; confidence 0.9 where a joint is present.
    """
    rng = np.random.default_rng(seed)
    t = np.arange(frames, dtype=np.float64) + phase
    swing = np.sin(2 * np.pi * t / period)  # [T]
    leg, arm = legs * height, arms * height
    head = 0.12 * height
    trunk = height - head - leg
    out = np.zeros((frames, len(BODY25), 2))

    def put(name: str, xy: np.ndarray) -> None:
        out[:, J(name)] = xy

    def limb(start: np.ndarray, length: float, angle: np.ndarray) -> np.ndarray:
        """End of a bone of ``length`` hanging down from ``start`` turned by ``angle`` (radians) [T] -> [T, 2]."""
        return start + length * np.stack([np.sin(angle), np.cos(angle)], axis=-1)

    bob = 0.01 * height * np.cos(4 * np.pi * t / period)
    mid_hip = np.stack([root_x + drift * np.arange(frames) / max(frames - 1, 1),
                        feet_y - leg + bob], axis=-1)  # [T, 2]
    neck = mid_hip + [0.03 * height, -trunk]
    put("mid_hip", mid_hip)
    put("neck", neck)
    put("nose", neck + [0.04 * height, -np.sqrt(head**2 - (0.04 * height) ** 2)])
    for side, sign in (("l", 1.0), ("r", -1.0)):
        half = sign * 0.5 * shoulders * height * 0.5  # three-quarter view: widths at half
        shoulder = neck + [half, 0.0]
        hip = mid_hip + [0.5 * half, 0.0]
        elbow = limb(shoulder, arm * 0.5, 0.5 * sign * swing)
        wrist = limb(elbow, arm * 0.5, 0.5 * sign * swing - 0.4 * (1 + sign * swing) / 2)
        knee = limb(hip, leg * 0.5, -0.4 * sign * swing)
        ankle = limb(knee, leg * 0.5, -0.4 * sign * swing + 0.3 * np.clip(sign * swing, 0, None))
        put(f"{side}_shoulder", shoulder)
        put(f"{side}_hip", hip)
        put(f"{side}_elbow", elbow)
        put(f"{side}_wrist", wrist)
        put(f"{side}_knee", knee)
        put(f"{side}_ankle", ankle)
        put(f"{side}_big_toe", ankle + [0.08 * height, 0.02 * height])
        put(f"{side}_small_toe", ankle + [0.07 * height, 0.025 * height])
        put(f"{side}_heel", ankle + [-0.02 * height, 0.02 * height])
        put(f"{side}_eye", out[:, J("nose")] + [0.015 * height + 0.5 * half * 0.2, -0.02 * height])
        put(f"{side}_ear", out[:, J("nose")] + [-0.03 * height + half * 0.2, -0.015 * height])
    out += rng.normal(0.0, 0.002 * height, out.shape)
    conf = np.full(out.shape[:2], 0.9)
    if dropped > 0:
        lost = rng.random(conf.shape) < dropped  # [T, J]
        lost[:, BODY25.indices(list(always_seen))] = False
        out[lost] = np.nan
        conf[lost] = 0.0
    return PoseTrack(out.astype(np.float32), conf.astype(np.float32), fps, image_size, "body25")


def tall_and_small(frames: int = 96, **common: object) -> dict[str, PoseTrack]:
    """Two people unlike each other in size and build: a tall long-legged one and a small long-armed one.

    Both lose 2 % of their joints (``common`` overrides that and other :func:`walking_figure` arguments).
    """
    common = {"dropped": 0.02, **common}
    return {
        "tall": walking_figure(frames, height=420.0, legs=0.56, arms=0.36, shoulders=0.18, feet_y=650.0,
                               root_x=300.0, seed=1, **common),
        "small": walking_figure(frames, height=260.0, legs=0.42, arms=0.44, shoulders=0.26, feet_y=600.0,
                                root_x=420.0, drift=30.0, period=26.0, phase=5.0, seed=2, **common),
    }
