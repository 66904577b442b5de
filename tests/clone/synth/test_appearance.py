"""Looks and characters: named, seeded, and validated."""

from __future__ import annotations

import pytest

from clone.synth import NAMED_LOOKS, Look, get_character, get_look, look_from_seed
from pose_io import InputError
from retarget.world.characters import NAMED_CHARACTERS


def test_looks_from_seeds_are_reproducible_and_varied() -> None:
    assert look_from_seed(3) == look_from_seed(3)
    looks = [look_from_seed(s) for s in range(12)]
    assert len({look.top for look in looks}) > 8
    assert len({look.shape.thigh for look in looks}) > 8
    assert get_look("5") == look_from_seed(5)


def test_every_named_character_has_a_look() -> None:
    for name in NAMED_CHARACTERS:
        assert get_look(name).name == name
    assert set(NAMED_LOOKS) <= set(NAMED_CHARACTERS)
    # A name without a designed look still gets one, the same every time.
    assert get_look("somebody_new") == get_look("somebody_new")
    assert get_look("somebody_new").name == "somebody_new"


def test_get_character_by_name_or_seed() -> None:
    skeleton, look, seed = get_character("child")
    assert skeleton is NAMED_CHARACTERS["child"] and look.name == "child" and seed is None
    skeleton, look, seed = get_character("42")
    assert seed == 42 and skeleton.name == "seed:42"
    assert get_character(42)[0] == skeleton
    with pytest.raises(InputError, match="tall_long_legs"):
        get_character("giant")


def test_look_rejects_unknown_styles() -> None:
    with pytest.raises(ValueError, match="sleeves"):
        Look(sleeves="puffy")
