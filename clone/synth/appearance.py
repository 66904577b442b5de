"""How a synthetic performer looks: body shape (limb thickness, torso and head size), skin, hair and clothes.

A :class:`Look` is plain data; :mod:`clone.synth.body` turns it and projected joints into frames. The
skeleton (bone lengths) comes from the motion world; the look adds everything a skeleton does not fix, so a
pose-to-frame generator has a real, person-shaped appearance to learn.

Looks are made three ways: by name (``NAMED_LOOKS``, matching the motion world's named characters), from
an integer seed (:func:`look_from_seed`), or through :func:`get_look`, which takes either and gives any
other name a stable look of its own.
"""

from __future__ import annotations

import colorsys
import dataclasses
import zlib
from dataclasses import dataclass, field

import numpy as np

from pose_io.errors import InputError
from retarget.world.characters import NAMED_CHARACTERS, sample_skeleton
from retarget.world.skeleton import Skeleton

RGB = tuple[int, int, int]

_AVERAGE_HEIGHT = 1.75  # metres; BodyShape's defaults are for this height

SLEEVES = ("long", "short", "none")
BOTTOMS = ("trousers", "shorts", "skirt")
PATTERNS = ("plain", "stripes", "checks")
HAIR_STYLES = ("short", "long", "bald")


@dataclass(frozen=True)
class BodyShape:
    """Thickness of the body around the skeleton, in metres (an average adult by default).

    Limb radii are ``(at the parent joint, at the child joint)``; limbs are tapered capsules between
    them. The torso is an elliptic cylinder: its half width is half the shoulder (hip) span plus a
    pad, its half depth is given directly.

    Attributes:
        head_radius: half width of the head; the head is a little taller than wide.
        neck_radius: radius of the neck.
        shoulder_pad: how far the torso reaches beyond each shoulder joint, sideways.
        hip_pad: how far the pelvis reaches beyond each hip joint, sideways.
        chest_depth: half the front-to-back depth of the chest.
        hip_depth: half the front-to-back depth of the pelvis.
        waist: waist width as a fraction of the chest/hip mean (1 = straight sides).
        upper_arm, forearm, thigh, shin: capsule radii (parent end, child end).
        hand_radius, hand_length: a hand is a capsule continuing the forearm past the wrist.
        foot_radius: radius of the foot capsule from heel to big toe.
        heel: how far the heel sticks out behind the ankle.
    """

    head_radius: float = 0.09
    neck_radius: float = 0.056
    shoulder_pad: float = 0.035
    hip_pad: float = 0.075
    chest_depth: float = 0.11
    hip_depth: float = 0.10
    waist: float = 0.86
    upper_arm: tuple[float, float] = (0.052, 0.042)
    forearm: tuple[float, float] = (0.041, 0.030)
    hand_radius: float = 0.033
    hand_length: float = 0.085
    thigh: tuple[float, float] = (0.083, 0.056)
    shin: tuple[float, float] = (0.054, 0.038)
    foot_radius: float = 0.038
    heel: float = 0.05

    def scaled(self, girth: float = 1.0, head: float = 1.0) -> BodyShape:
        """This shape with every thickness times ``girth`` and the head times ``head``."""
        def s(v: float | tuple[float, float]) -> float | tuple[float, float]:
            return (v[0] * girth, v[1] * girth) if isinstance(v, tuple) else v * girth

        changes = {f.name: s(getattr(self, f.name)) for f in dataclasses.fields(self)
                   if f.name not in ("head_radius", "waist", "hand_length", "heel")}
        return dataclasses.replace(self, head_radius=self.head_radius * head, **changes)


@dataclass(frozen=True)
class Backdrop:
    """The fixed background of one video: a wall over a floor, with a little seeded texture.

    Attributes:
        wall_top, wall_bottom: RGB of the wall's vertical gradient.
        floor_near, floor_far: RGB of the floor, near the camera and at the wall.
        texture_seed: seed of the wall's noise and the floor's boards.
        board_width: floor boards' width as a fraction of the canvas width.
    """

    wall_top: RGB = (196, 204, 212)
    wall_bottom: RGB = (168, 176, 186)
    floor_near: RGB = (120, 96, 72)
    floor_far: RGB = (146, 120, 94)
    texture_seed: int = 0
    board_width: float = 0.11


@dataclass(frozen=True)
class Look:
    """Everything about a synthetic performer's appearance except bone lengths.

    Attributes:
        name: a label (the character's name, or ``"seed:N"``).
        shape: thickness of the body.
        skin, hair: RGB.
        hair_style: one of ``HAIR_STYLES``.
        top, top_accent: RGB of the shirt and of its pattern.
        sleeves: one of ``SLEEVES`` (``"long"`` covers the forearm, ``"short"`` the upper arm only).
        pattern: shirt pattern, one of ``PATTERNS``.
        pattern_period: length of one stripe/check period in metres, along the body.
        bottom: RGB of trousers, shorts or skirt.
        bottom_style: one of ``BOTTOMS``.
        belt: RGB of the waistband.
        shoes: RGB.
        backdrop: the video's background.
    """

    name: str = "average"
    shape: BodyShape = field(default_factory=BodyShape)
    skin: RGB = (224, 172, 138)
    hair: RGB = (64, 42, 28)
    hair_style: str = "short"
    top: RGB = (52, 98, 168)
    top_accent: RGB = (230, 230, 222)
    sleeves: str = "short"
    pattern: str = "stripes"
    pattern_period: float = 0.09
    bottom: RGB = (48, 52, 66)
    bottom_style: str = "trousers"
    belt: RGB = (40, 30, 24)
    shoes: RGB = (30, 30, 34)
    backdrop: Backdrop = field(default_factory=Backdrop)

    def __post_init__(self) -> None:
        for attr, valid in (("sleeves", SLEEVES), ("bottom_style", BOTTOMS), ("pattern", PATTERNS),
                            ("hair_style", HAIR_STYLES)):
            if getattr(self, attr) not in valid:
                raise ValueError(f"look {self.name}: {attr} {getattr(self, attr)!r} is not one of {', '.join(valid)}")
        if self.pattern_period <= 0:
            raise ValueError(f"look {self.name}: pattern_period must be positive")

    def to_dict(self) -> dict:
        """Plain-data form (for meta files)."""
        return dataclasses.asdict(self)


NAMED_LOOKS: dict[str, Look] = {
    "average": Look(name="average"),
    "tall_long_legs": Look(
        name="tall_long_legs",
        shape=BodyShape().scaled(girth=0.92),
        skin=(141, 96, 70), hair=(22, 18, 16), hair_style="short",
        top=(196, 64, 52), top_accent=(250, 214, 120), sleeves="long", pattern="checks", pattern_period=0.12,
        bottom=(36, 58, 94), bottom_style="trousers", belt=(20, 20, 20), shoes=(214, 214, 206),
        backdrop=Backdrop(wall_top=(214, 206, 186), wall_bottom=(190, 180, 160), floor_near=(92, 96, 102),
                          floor_far=(118, 122, 128), texture_seed=11, board_width=0.16),
    ),
    "short_stocky": Look(
        name="short_stocky",
        shape=dataclasses.replace(BodyShape().scaled(girth=1.32, head=1.06), waist=0.98, chest_depth=0.16,
                                  hip_depth=0.14),
        skin=(236, 190, 160), hair=(150, 80, 40), hair_style="short",
        top=(60, 140, 76), top_accent=(24, 70, 36), sleeves="short", pattern="stripes", pattern_period=0.07,
        bottom=(110, 92, 70), bottom_style="shorts", belt=(60, 40, 20), shoes=(120, 60, 30),
        backdrop=Backdrop(wall_top=(176, 196, 214), wall_bottom=(150, 170, 190), floor_near=(132, 110, 80),
                          floor_far=(160, 136, 104), texture_seed=23, board_width=0.09),
    ),
    "child": Look(
        name="child",
        shape=dataclasses.replace(BodyShape().scaled(girth=0.74, head=0.95), waist=0.95, hip_pad=0.05),
        skin=(232, 182, 150), hair=(206, 160, 90), hair_style="long",
        top=(236, 196, 60), top_accent=(220, 80, 120), sleeves="short", pattern="checks", pattern_period=0.06,
        bottom=(200, 70, 110), bottom_style="skirt", belt=(150, 40, 80), shoes=(60, 90, 180),
        backdrop=Backdrop(wall_top=(222, 214, 230), wall_bottom=(200, 190, 210), floor_near=(150, 128, 104),
                          floor_far=(178, 156, 130), texture_seed=37, board_width=0.12),
    ),
    "long_arms": Look(
        name="long_arms",
        shape=BodyShape().scaled(girth=0.97),
        skin=(198, 140, 104), hair=(22, 18, 16), hair_style="long",
        top=(238, 238, 232), top_accent=(40, 40, 48), sleeves="none", pattern="stripes", pattern_period=0.05,
        bottom=(70, 100, 150), bottom_style="trousers", belt=(90, 60, 30), shoes=(150, 40, 40),
        backdrop=Backdrop(wall_top=(190, 214, 200), wall_bottom=(166, 190, 176), floor_near=(110, 84, 62),
                          floor_far=(136, 108, 84), texture_seed=53, board_width=0.14),
    ),
}

_SKINS: tuple[RGB, ...] = ((244, 204, 178), (232, 182, 150), (224, 172, 138), (198, 140, 104), (160, 110, 80),
                           (141, 96, 70), (104, 70, 50), (80, 54, 40))
_HAIRS: tuple[RGB, ...] = ((22, 18, 16), (64, 42, 28), (110, 70, 40), (150, 80, 40), (206, 160, 90),
                           (170, 170, 168))


def _hsv(h: float, s: float, v: float) -> RGB:
    r, g, b = colorsys.hsv_to_rgb(h % 1.0, s, v)
    return (round(r * 255), round(g * 255), round(b * 255))


def look_from_seed(seed: int) -> Look:
    """A random but reproducible look: body shape, skin, hair, clothes, pattern and backdrop.

    Clothes get hues far enough apart that shirt, trousers and backdrop stay distinguishable.

    Args:
        seed: any integer; the same seed always gives the same look.
    """
    rng = np.random.default_rng([int(seed) & 0xFFFFFFFF, 0x100C])
    girth = float(rng.uniform(0.82, 1.3))
    shape = dataclasses.replace(
        BodyShape().scaled(girth=girth, head=float(rng.uniform(0.92, 1.08))),
        waist=float(rng.uniform(0.8, 1.0)),
        chest_depth=0.11 * girth * float(rng.uniform(0.9, 1.15)),
        hip_depth=0.10 * girth * float(rng.uniform(0.9, 1.15)),
    )
    top_hue = float(rng.uniform())
    bottom_hue = top_hue + float(rng.uniform(0.25, 0.75))
    wall_hue = top_hue + float(rng.uniform(0.35, 0.65))
    wall = _hsv(wall_hue, float(rng.uniform(0.05, 0.2)), float(rng.uniform(0.72, 0.88)))
    floor_hue = float(rng.uniform(0.05, 0.12))
    floor_v = float(rng.uniform(0.4, 0.62))
    top = _hsv(top_hue, float(rng.uniform(0.45, 0.85)), float(rng.uniform(0.45, 0.9)))
    # The accent is either a light or a dark variant of a nearby hue, so the pattern always shows.
    top_v = colorsys.rgb_to_hsv(*(c / 255 for c in top))[2]
    accent = _hsv(top_hue + float(rng.uniform(-0.15, 0.15)), float(rng.uniform(0.1, 0.6)),
                  0.95 if top_v < 0.65 else 0.25)
    return Look(
        name=f"seed:{int(seed)}",
        shape=shape,
        skin=_SKINS[int(rng.integers(len(_SKINS)))],
        hair=_HAIRS[int(rng.integers(len(_HAIRS)))],
        hair_style=str(rng.choice(HAIR_STYLES, p=[0.6, 0.3, 0.1])),
        top=top,
        top_accent=accent,
        sleeves=str(rng.choice(SLEEVES, p=[0.4, 0.45, 0.15])),
        pattern=str(rng.choice(PATTERNS, p=[0.3, 0.4, 0.3])),
        pattern_period=float(rng.uniform(0.05, 0.14)),
        bottom=_hsv(bottom_hue, float(rng.uniform(0.2, 0.7)), float(rng.uniform(0.2, 0.6))),
        bottom_style=str(rng.choice(BOTTOMS, p=[0.6, 0.25, 0.15])),
        belt=_hsv(float(rng.uniform()), 0.3, float(rng.uniform(0.1, 0.3))),
        shoes=_hsv(float(rng.uniform()), float(rng.uniform(0.0, 0.6)), float(rng.uniform(0.1, 0.9))),
        backdrop=Backdrop(
            wall_top=wall,
            wall_bottom=tuple(round(c * 0.88) for c in wall),  # type: ignore[arg-type]
            floor_near=_hsv(floor_hue, 0.45, floor_v),
            floor_far=_hsv(floor_hue, 0.4, min(1.0, floor_v * 1.2)),
            texture_seed=int(rng.integers(1 << 31)),
            board_width=float(rng.uniform(0.07, 0.18)),
        ),
    )


def get_look(name_or_seed: str | int) -> Look:
    """The look of a named character, or of a seed.

    A name in ``NAMED_LOOKS`` gives that look; an integer (or a string of digits) gives
    :func:`look_from_seed`; any other name (a character the motion world has but this table does not)
    gets a stable look seeded from the name, so every character is always rendered the same way.
    """
    if isinstance(name_or_seed, int) or str(name_or_seed).lstrip("-").isdigit():
        return look_from_seed(int(name_or_seed))
    name = str(name_or_seed)
    if name in NAMED_LOOKS:
        return NAMED_LOOKS[name]
    return dataclasses.replace(look_from_seed(zlib.crc32(name.encode("utf-8"))), name=name)


def get_character(name_or_seed: str | int) -> tuple[Skeleton, Look, int | None]:
    """A whole character: bone lengths and look, by name or integer seed.

    A name must be one of the motion world's ``NAMED_CHARACTERS``; a seed samples the skeleton with
    ``sample_skeleton(np.random.default_rng(seed))`` and the look with :func:`look_from_seed`, its
    thickness scaled with the skeleton's height.

    Returns:
        ``(skeleton, look, seed or None)``.

    Raises:
        InputError: an unknown name (the message lists the valid names).
    """
    text = str(name_or_seed).strip()
    if isinstance(name_or_seed, int) or text.lstrip("-").isdigit():
        seed = int(text)
        skeleton = dataclasses.replace(sample_skeleton(np.random.default_rng(seed)), name=f"seed:{seed}")
        look = look_from_seed(seed)
        # Thickness grows with the body; heads less so (children have relatively big heads).
        size = float(np.clip(skeleton.height / _AVERAGE_HEIGHT, 0.6, 1.2))
        return skeleton, dataclasses.replace(look, shape=look.shape.scaled(girth=size, head=size ** 0.4)), seed
    if text not in NAMED_CHARACTERS:
        raise InputError(f"unknown character {text!r}; valid: {', '.join(NAMED_CHARACTERS)} or an integer seed")
    return NAMED_CHARACTERS[text], get_look(text), None
