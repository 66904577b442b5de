"""Characters of the motion world: human proportions by height, random characters and the named ones.

Proportions are fractions of standing height. Adults after anthropometric tables (segment lengths of Drillis &
Contini as tabulated by Winter, joint-centre to joint-centre); children (about 1.1 m) have a bigger head and
shorter legs. Between 1.1 m and 1.55 m the two are blended.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from retarget.world.skeleton import Skeleton

_ADULT = {
    "hip": 0.050, "thigh": 0.245, "shin": 0.247, "foot": 0.080, "torso": 0.260, "shoulder": 0.100,
    "upper_arm": 0.186, "forearm": 0.146, "neck": 0.130, "face": 0.060,
}
_CHILD = {
    "hip": 0.055, "thigh": 0.222, "shin": 0.226, "foot": 0.085, "torso": 0.280, "shoulder": 0.105,
    "upper_arm": 0.175, "forearm": 0.135, "neck": 0.150, "face": 0.085,
}
MIN_HEIGHT = 1.10
MAX_HEIGHT = 2.05
_ADULT_FROM = 1.55


def make_skeleton(
    height: float,
    legs: float = 1.0,
    torso: float = 1.0,
    arms: float = 1.0,
    neck: float = 1.0,
    shoulders: float = 1.0,
    hips: float = 1.0,
    head: float = 1.0,
    feet: float = 1.0,
    thigh_shin: float = 1.0,
    upper_fore: float = 1.0,
    name: str = "",
) -> Skeleton:
    """A symmetric character of standing ``height`` with the given proportion factors.

    Each factor multiplies a body part's share (1 = typical proportions for that height); the whole is
    then scaled so that ``Skeleton.height`` equals ``height`` exactly.

    Args:
        height: standing height in metres.
        legs, torso, arms, neck, shoulders, hips, head, feet: relative sizes (shoulders, hips: half widths).
        thigh_shin: thigh / shin ratio factor (the leg's length is kept).
        upper_fore: upper arm / forearm ratio factor (the arm's length is kept).
        name: label.
    """
    w = float(np.clip((height - MIN_HEIGHT) / (_ADULT_FROM - MIN_HEIGHT), 0.0, 1.0))
    f = {k: (1 - w) * _CHILD[k] + w * _ADULT[k] for k in _ADULT}
    leg = (f["thigh"] + f["shin"]) * legs
    thigh = leg * f["thigh"] * thigh_shin / (f["thigh"] * thigh_shin + f["shin"])
    arm = (f["upper_arm"] + f["forearm"]) * arms
    upper = arm * f["upper_arm"] * upper_fore / (f["upper_arm"] * upper_fore + f["forearm"])
    lengths = {
        "neck": f["torso"] * torso, "head": f["neck"] * neck, "nose": f["face"] * head,
    }
    for side in "lr":
        lengths.update({
            f"{side}_hip": f["hip"] * hips, f"{side}_knee": thigh, f"{side}_ankle": leg - thigh,
            f"{side}_big_toe": f["foot"] * feet, f"{side}_shoulder": f["shoulder"] * shoulders,
            f"{side}_elbow": upper, f"{side}_wrist": arm - upper,
        })
    skel = Skeleton.from_dict(lengths, name)
    return skel.scaled(height / skel.height)


# Log-normal spreads of the independent proportion factors of ``sample_skeleton``.
_SPREAD = {
    "legs": 0.06, "torso": 0.07, "arms": 0.06, "neck": 0.12, "shoulders": 0.10, "hips": 0.12,
    "head": 0.08, "feet": 0.08, "thigh_shin": 0.05, "upper_fore": 0.05,
}
_CHILD_SHARE = 0.25
_ADULT_MIN = 1.50


def sample_skeleton(rng: np.random.Generator, spread: float = 1.0) -> Skeleton:
    """A random human character.

    The height is uniform in 1.10-1.50 m (a quarter of the draws: children and teenagers) or in
    1.50-2.05 m (adults); legs, torso, arms, neck, shoulder and hip width, head, feet and the two
    limb ratios vary independently (log-normal, clipped at 2.5 sigma).

    Args:
        rng: the random generator (the only source of randomness).
        spread: factor on every proportion's log-normal sigma (1: the world's test characters).
    """
    if rng.random() < _CHILD_SHARE:
        height = rng.uniform(MIN_HEIGHT, _ADULT_MIN)
    else:
        height = rng.uniform(_ADULT_MIN, MAX_HEIGHT)
    factors = {k: float(np.exp(np.clip(rng.normal(), -2.5, 2.5) * s * spread)) for k, s in _SPREAD.items()}
    return make_skeleton(height, **factors)


NAMED_CHARACTERS: dict[str, Skeleton] = {
    "average": make_skeleton(1.75, name="average"),
    "tall_long_legs": make_skeleton(2.00, legs=1.12, torso=0.93, name="tall_long_legs"),
    "short_stocky": make_skeleton(
        1.55, legs=0.88, torso=1.06, arms=0.92, neck=0.8, shoulders=1.25, hips=1.2, name="short_stocky"
    ),
    "child": make_skeleton(1.15, name="child"),
    "long_arms": make_skeleton(1.80, arms=1.13, torso=0.94, shoulders=1.08, name="long_arms"),
}


def log_proportions(characters: Sequence[Skeleton]) -> np.ndarray:
    """[C, bones] log(bone length / skeleton height) of each character: its proportions, size removed."""
    return np.log(np.array([c.array / c.height for c in characters]))


def standard_proportions(characters: Sequence[Skeleton]) -> np.ndarray:
    """[C, bones] :func:`log_proportions` standardised over these characters (each bone: mean 0, std 1): what
    the skeleton-proportion term and the proportion probe compare codes with."""
    logs = log_proportions(characters)
    return (logs - logs.mean(axis=0)) / (logs.std(axis=0) + 1e-9)


__all__ = [
    "MAX_HEIGHT", "MIN_HEIGHT", "NAMED_CHARACTERS", "log_proportions", "make_skeleton", "sample_skeleton",
    "standard_proportions",
]
