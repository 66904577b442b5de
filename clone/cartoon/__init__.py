"""Video-driven cartoons (Aberman et al. 2019, Sec. 7): a driver's motion on a character of exaggerated proportions.

- ``character``: :class:`CharacterSpec`, :data:`PRESETS`, :func:`load_character` (preset name or JSON file).
- ``reference``: the character's reference track, rendered with the motion world's skeleton and camera.
- ``proportions``: the forward-kinematics fix that holds the limb lengths, and the limb-length error.
- ``draw``: the flat cartoon drawing.
- ``make``: :func:`make_cartoon`, the whole pipeline and its report.
"""

from clone.cartoon.character import PARTS, PRESETS, CharacterSpec, load_character
from clone.cartoon.draw import CartoonLook, Palette, cartoon_frames, draw_cartoon
from clone.cartoon.make import Cartoon, make_cartoon, summary_lines

__all__ = [
    "PARTS",
    "PRESETS",
    "Cartoon",
    "CartoonLook",
    "CharacterSpec",
    "Palette",
    "cartoon_frames",
    "draw_cartoon",
    "load_character",
    "make_cartoon",
    "summary_lines",
]
