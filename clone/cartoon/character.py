"""Cartoon characters: body proportions relative to a standard body, as presets or a JSON file.

A character multiplies the bone lengths of the motion world's standard body (``NAMED_CHARACTERS["average"]``,
1.75 m) part by part: ``{"name": "stubby", "legs": 0.55}`` halves the legs and leaves everything else as it is
(the character is then shorter; ``scale`` multiplies the whole body). Parts that overlap multiply: ``arms``
and ``forearms`` both act on the forearms. The parts and the bones of
:data:`retarget.world.skeleton.BONES` they act on are :data:`PARTS`.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType

from pose_io.errors import InputError
from retarget.world.characters import NAMED_CHARACTERS
from retarget.world.skeleton import BONE_NAMES, Skeleton

# Part -> the world bones it scales (a bone is named after its child joint: "l_knee" is the left thigh, "head"
# runs from the shoulders up to the centre of the skull, "nose" from there to the face).
PARTS: Mapping[str, tuple[str, ...]] = MappingProxyType({
    "head": ("head", "nose"),
    "torso": ("neck",),
    "shoulders": ("l_shoulder", "r_shoulder"),
    "hips": ("l_hip", "r_hip"),
    "arms": ("l_elbow", "l_wrist", "r_elbow", "r_wrist"),
    "upper_arms": ("l_elbow", "r_elbow"),
    "forearms": ("l_wrist", "r_wrist"),
    "legs": ("l_knee", "l_ankle", "r_knee", "r_ankle"),
    "thighs": ("l_knee", "r_knee"),
    "shins": ("l_ankle", "r_ankle"),
    "feet": ("l_big_toe", "r_big_toe"),
})
# A factor outside this range is almost certainly a typo (a length in metres, a percentage).
FACTOR_RANGE = (0.2, 5.0)
STANDARD: Skeleton = NAMED_CHARACTERS["average"]


def _is_number(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


@dataclass(frozen=True)
class CharacterSpec:
    """A cartoon character's proportions.

    Attributes:
        name: label.
        factors: part name (:data:`PARTS`) -> factor on the standard body's length of that part.
        scale: factor on the whole body.
    """

    name: str
    factors: Mapping[str, float] = field(default_factory=dict)
    scale: float = 1.0

    def __post_init__(self) -> None:
        unknown = sorted(set(self.factors) - set(PARTS))
        if unknown:
            raise InputError(f"character {self.name!r}: unknown parts {', '.join(unknown)}; valid: {', '.join(PARTS)}")
        for part, value in {**self.factors, "scale": self.scale}.items():
            if not _is_number(value) or not FACTOR_RANGE[0] <= float(value) <= FACTOR_RANGE[1]:
                raise InputError(
                    f"character {self.name!r}: {part} must be a number in {FACTOR_RANGE[0]}..{FACTOR_RANGE[1]}"
                    f" (a factor on the standard body), got {value!r}"
                )
        object.__setattr__(self, "factors", MappingProxyType({k: float(v) for k, v in self.factors.items()}))
        object.__setattr__(self, "scale", float(self.scale))

    def bone_factors(self) -> dict[str, float]:
        """World bone name -> product of the factors acting on it (and ``scale``)."""
        out = dict.fromkeys(BONE_NAMES, self.scale)
        for part, factor in self.factors.items():
            for bone in PARTS[part]:
                out[bone] *= factor
        return out

    def skeleton(self) -> Skeleton:
        """The character's 3D skeleton: the standard body's bones times :meth:`bone_factors`."""
        factors = self.bone_factors()
        return Skeleton.from_dict({b: STANDARD.length(b) * factors[b] for b in BONE_NAMES}, self.name)

    def to_dict(self) -> dict[str, object]:
        """The JSON form :func:`load_character` reads."""
        return {"name": self.name, "scale": self.scale, **self.factors}


PRESETS: Mapping[str, CharacterSpec] = MappingProxyType({
    spec.name: spec
    for spec in (
        CharacterSpec("standard"),
        CharacterSpec("bighead", {"head": 2.0}),
        CharacterSpec("stubby", {"legs": 0.55, "hips": 1.3}),
        CharacterSpec("longarms", {"arms": 1.45}),
        CharacterSpec("chibi", {"head": 2.3, "legs": 0.6, "arms": 0.65, "torso": 0.75}),
    )
})


def load_character(spec: str | Path) -> CharacterSpec:
    """A preset by name, or a JSON file ``{"name": ..., "scale": ..., "<part>": factor, ...}``.

    Raises:
        InputError: neither a preset nor a file, unreadable or invalid JSON, unknown parts, bad factors.
    """
    text = str(spec)
    if text in PRESETS:
        return PRESETS[text]
    path = Path(text)
    if not path.is_file():
        raise InputError(f"character {text!r}: not a preset ({', '.join(PRESETS)}) nor a JSON file")
    try:
        data = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise InputError(f"{path}: cannot read the character ({exc})") from None
    if not isinstance(data, dict):
        raise InputError(f"{path}: a character is a JSON object of part factors, e.g. {{\"legs\": 0.6}}")
    name = data.pop("name", path.stem)
    if not isinstance(name, str) or not name:
        raise InputError(f"{path}: name must be a non-empty string")
    scale = data.pop("scale", 1.0)
    try:
        return CharacterSpec(name, data, scale)
    except InputError as exc:
        raise InputError(f"{path}: {exc}") from None
