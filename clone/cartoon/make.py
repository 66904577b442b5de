"""Video-driven cartoons (Aberman et al. 2019, Sec. 7): a driver's motion performed by a cartoon character.

1. The character's reference track is rendered (:mod:`clone.cartoon.reference`) standing where the driver
   stands, at the driver's scale, from a chosen yaw or from the driver's (estimated) yaw.
2. The network takes its skeleton code from that track, and its view code from the same track (``yaw`` given)
   or from the driver (the character is then seen as the driver is), and retargets the driver onto them.
3. The limbs along the body get the character's lengths in every frame
   (:func:`~clone.cartoon.proportions.hold_lengths`).

The report measures, against the character's limb lengths: the network's output before that fix, Everybody
Dance Now's global scaling against the same reference track, the driver as it is, and the character's own
reference track (what a moving body's foreshortening alone costs); and how much the fix moved the joints.
"""

from __future__ import annotations

import dataclasses
import logging
from dataclasses import dataclass

import numpy as np

from clone.cartoon.character import CharacterSpec
from clone.cartoon.draw import CartoonLook
from clone.cartoon.proportions import displacement, held_limbs, hold_lengths, proportion_error
from clone.cartoon.reference import character_lengths, estimate_yaw, framing_of, reference_track, rest_joints
from pose_io.track import PoseTrack
from retarget.api import Retargeter
from retarget.baselines.methods import global_scale_retarget
from retarget.inference.tracks import body15_track, filled_body15
from retarget.network.preprocess import LAYOUT

log = logging.getLogger(__name__)

# The head: radius and centre in units of the character's neck-to-nose length (a cartoon's big round head).
HEAD_RADIUS = 0.85
HEAD_OFFSET = 1.3


@dataclass(frozen=True, eq=False)
class Cartoon:
    """A driver's motion performed by a cartoon character.

    Attributes:
        track: body15 poses with the character's proportions, in the driver's frame.
        network: the network's output before the proportion fix.
        reference: the character's reference track the codes came from.
        lengths: [L] the character's limb lengths in pixels (``LAYOUT.limbs`` order).
        look: sizes for drawing.
        report: the measures (JSON-ready).
    """

    track: PoseTrack
    network: PoseTrack
    reference: PoseTrack
    lengths: np.ndarray
    look: CartoonLook
    report: dict


def make_cartoon(
    driver: PoseTrack, spec: CharacterSpec, retargeter: Retargeter, yaw: float | None = None, name: str = "driver"
) -> Cartoon:
    """Retarget ``driver`` onto the character ``spec`` and hold its proportions.

    Args:
        driver: the driver's poses (any layout convertible to body15).
        spec: the character.
        retargeter: the network.
        yaw: the character's view in degrees (0 = front, +90 = its left side); None = the driver's view.
        name: how error messages call the driver.

    Returns:
        The cartoon's poses, the intermediate tracks and the report.

    Raises:
        InputError: a driver the network cannot take (too short, joints never seen).
    """
    view_yaw = estimate_yaw(driver, name) if yaw is None else yaw
    framing = framing_of(driver, view_yaw, name)
    reference = reference_track(spec, framing, driver.fps)
    codes = retargeter.reference_codes(reference, None if yaw is not None else driver, name="character reference",
                                       view_name=name)
    network = retargeter.retarget(driver, codes, name=name)
    lengths, height = character_lengths(reference)
    rest = rest_joints(spec, framing)
    held = hold_lengths(network.joints, np.where(held_limbs(), lengths, np.nan), rest)
    scaled = global_scale_retarget(driver, reference).joints
    report = {
        "character": spec.to_dict(),
        "view": f"driver's (yaw estimated {view_yaw:.0f})" if yaw is None else f"yaw {yaw:g}",
        "yaw": view_yaw,
        "frames": len(driver),
        "height_px": height,
        "limb_error_pct": {
            "network": proportion_error(network.joints, lengths, height),
            "global_scale": proportion_error(scaled, lengths, height),
            "driver": proportion_error(filled_body15(driver, name), lengths, height),
            "reference": proportion_error(reference.joints, lengths, height),
            "after_fix": proportion_error(held, lengths, height),
        },
        "fix_moved_pct": displacement(network.joints, held, height),
        "limbs_held": [f"{a}-{b}" for (a, b), h in zip(LAYOUT.limbs, held_limbs()) if h],
    }
    front = rest_joints(spec, dataclasses.replace(framing, yaw=0.0))
    neck_nose = float(lengths[LAYOUT.limbs.index(("neck", "nose"))])
    look = CartoonLook(
        height=height,
        head_radius=HEAD_RADIUS * neck_nose,
        head_offset=HEAD_OFFSET,
        shoulder_width=float(front[LAYOUT.index("l_shoulder"), 0] - front[LAYOUT.index("r_shoulder"), 0]),
        ground_y=framing.placement.ground_y,
    )
    track = body15_track(held, driver.fps, network.image_size)
    return Cartoon(track, network, reference, lengths, look, report)


def summary_lines(report: dict) -> list[str]:
    """The report in a few lines for the terminal."""
    err = report["limb_error_pct"]
    moved = report["fix_moved_pct"]
    character = (
        f"character {report['character']['name']} ({report['view']}, {report['frames']} frames, "
        f"{report['height_px']:.0f} px tall)"
    )
    limbs = (
        f"limb-length error vs the character, % of its height: network {err['network']['mean_pct']:.1f}, "
        f"global scaling {err['global_scale']['mean_pct']:.1f}, the driver as it is {err['driver']['mean_pct']:.1f} "
        f"(the character's own reference track {err['reference']['mean_pct']:.1f})"
    )
    fix = (
        f"proportion fix moved joints by {moved['mean_pct']:.1f} % of the height on average "
        f"(max {moved['max_pct']:.1f} %); after it the error is {err['after_fix']['mean_pct']:.2g}"
    )
    return [character, limbs, fix]
