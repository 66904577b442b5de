"""The demo's pairs on many motions: a cloning-kind measure of retargeting weights (`clone retarget eval-cloning`).

`clone demo` scores three drivers of one motion each. Here every clip of a motion-world split that is long enough
becomes the demo's three drivers (:data:`clone.demo.config.PAIRS`: the child at +30°, the reference's own body at
-30°, the child at -30°), each with its ground truth: the demo's reference character performing the clip, seen by
the reference's camera (+30°), kept only when it stays inside the frame as the demo's do. With ``turns``, a fourth
driver of kind ``turn``: the child at -30° turning its whole body by 90-360° either way during the case (one turn
drawn per clip, :func:`retarget.world.turns.draw_turn`), its truth turning alike: real dancers and fashion models
turn, the world's clips rarely do. With ``travel``, a driver of kind ``travel`` on every clip whose body travels
across the picture (at least half its height over the case): the child 50° from the reference's camera, turning as
the turning driver does on every other such clip, in a picture three times as wide as high (the demo's reference
rendered alike), its truth walking as far: a driver who walks across a room must keep its travel on the
reference's stage. Every driver is moved
onto the demo's reference track (:func:`clone.demo.scenes.reference_track`) the way `clone drive` does: the network
with the reference's skeleton and view codes, the foot skating cleaned with the driver's contacts, the track
started where the reference stands and kept inside the picture (:func:`clone.drive.poses.finish_driven`). The scores are the demo's primary measure, the RMSE of
the MidHip-aligned joints in % of the ground truth's height, and its placement, the MidHip's RMS distance from the
truth's (:func:`clone.metrics.track_gt_scores`). Everybody
Dance Now's global scaling is scored on the same pairs, its own way (:func:`clone.drive.poses.global_scale_to`, then
kept inside the picture).

Why it exists: the world's eval cases (`clone retarget eval`: 64-frame windows, any view and pitch, a 64-frame
reference) rank checkpoints in an order cloning does not follow; this measure follows the demo.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from clone.demo.config import DemoConfig
from pose_io.errors import InputError
from pose_io.track import PoseTrack
from retarget.evaluate.scores import mean_se

log = logging.getLogger(__name__)

Drive = Callable[["CloningCase"], PoseTrack]  # a case -> its driver moved onto the reference, in its pixels

# The demo whose pairs are copied (frozen, so a shared default is safe).
DEMO = DemoConfig()
# Clip frames before a case starts (mocap clips often open in a T-pose or a still stand).
CASE_START = 15
# The turning driver: its kind, body and camera (the demo's "both" pair), and the seed of the turns.
TURN_KIND = "turn"
TURN_CHARACTER, TURN_YAW = "child", -30.0
TURN_SEED = 2019
# The travelling driver: its kind, body and camera (50° from the reference's), the picture's width in heights, the
# least travel of the truth's MidHip (share of its height) that makes a clip one, and the seed of its turns.
TRAVEL_KIND = "travel"
TRAVEL_CHARACTER, TRAVEL_YAW = "child", -20.0
TRAVEL_WIDTH = 3
TRAVEL_LEAST = 0.5
TRAVEL_SEED = 7
# The pictures a case is set in: the demo's square frame, and the travelling driver's wide one.
SQUARE, WIDE = "square", "wide"


@dataclass(frozen=True)
class CloningCase:
    """One driver and its ground truth.

    Attributes:
        clip: the clip's path in the mocap folder (as the split lists it).
        kind: the demo pair it copies (``proportions``, ``view``, ``both``).
        driver: the driver's track as `clone drive` reads it (:func:`clone.drive.poses.driver_track`).
        truth: the reference character performing the same frames, seen by the reference's camera (body15).
        picture: the frame the case is set in (:data:`SQUARE`, the demo's; :data:`WIDE`, the travelling one's),
            the reference it is driven onto rendered alike (:func:`references`).
    """

    clip: str
    kind: str
    driver: PoseTrack
    truth: PoseTrack
    picture: str = SQUARE


def picture_size(config: DemoConfig, picture: str) -> tuple[int, int]:
    """(width, height) of a case's picture."""
    side = config.render_size
    return (TRAVEL_WIDTH * side, side) if picture == WIDE else (side, side)


def references(config: DemoConfig = DEMO) -> dict[str, PoseTrack]:
    """The demo's reference track in each picture (:data:`SQUARE`, :data:`WIDE`), standing at its centre."""
    from clone.demo.scenes import reference_track

    return {picture: reference_track(config, size=picture_size(config, picture)) for picture in (SQUARE, WIDE)}


def travel(track: PoseTrack) -> float:
    """How far the MidHip travels across the picture over the track, in shares of the body's height (the 90th
    percentile of its frames' heights)."""
    body = track.to_layout("body15")
    root = body.joint("mid_hip")[:, 0]
    heights = np.nanmax(body.joints[..., 1], axis=1) - np.nanmin(body.joints[..., 1], axis=1)
    height = float(np.nanpercentile(heights, 90))
    return float((np.nanmax(root) - np.nanmin(root)) / height) if height > 0 else 0.0


def cloning_cases(
    clips: Sequence[Mapping], mocap: str | Path, frames: int = 100, limit: int | None = None,
    config: DemoConfig = DEMO, fps: float = 30.0, turns: bool = False, travelling: bool = False,
) -> list[CloningCase]:  # fmt: skip
    """The demo's pairs on every usable clip, clips in the given order, at most ``limit`` of them.

    Args:
        clips: the split's clips (``WorldSplit.clips``: ``name``, ``path`` relative to ``mocap``, ``frames``).
        mocap: the motion-capture folder.
        frames: frames of a case, from frame :data:`CASE_START` of its clip.
        limit: the most clips to use (None: all).
        config: the demo whose reference and pairs are copied.
        fps: the world's frame rate.
        turns: add each clip's turning driver (kind :data:`TURN_KIND`; skipped where its truth leaves the frame).
        travelling: add the travelling driver (kind :data:`TRAVEL_KIND`, picture :data:`WIDE`) of every clip
            whose truth travels at least :data:`TRAVEL_LEAST` of its height and stays inside the wide frame (such
            a clip counts towards ``limit`` even when its truth leaves the square frame).

    Raises:
        InputError: no clip long enough whose ground truth stays inside the frame.
    """
    from clone.demo.scenes import stays_in_frame
    from clone.drive.poses import driver_track
    from clone.synth import get_character
    from clone.synth.performance import render_performance
    from retarget.world import load_motion
    from retarget.world.turns import draw_turn

    ref_skeleton, ref_look, _ = get_character(config.reference_character)
    cases: list[CloningCase] = []
    used = square = 0  # clips giving any case; clips whose truth stays in the square frame
    for clip in clips:
        if limit is not None and used >= limit:
            break
        if clip["frames"] < CASE_START + frames:
            continue
        motion = load_motion(Path(mocap) / clip["path"], fps=fps)
        window = {"size": config.render_size, "start": CASE_START, "frames": frames}
        found = len(cases)
        truth = render_performance(motion, ref_skeleton, ref_look, yaw=config.reference_yaw, **window)[1]
        if stays_in_frame(config, truth):
            square += 1
            for pair in config.pairs:
                skeleton, look, _ = get_character(pair.character)
                driver = render_performance(motion, skeleton, look, yaw=pair.yaw, **window)[1]
                cases.append(CloningCase(clip["path"], pair.name, driver_track(driver, name=clip["path"]),
                                         truth.to_layout("body15")))  # fmt: skip
            if turns:
                turn = draw_turn(np.random.default_rng([TURN_SEED, square]), frames)
                turned = render_performance(motion, ref_skeleton, ref_look, yaw=config.reference_yaw, turn=turn,
                                            **window)[1]  # fmt: skip
                if stays_in_frame(config, turned):
                    skeleton, look, _ = get_character(TURN_CHARACTER)
                    driver = render_performance(motion, skeleton, look, yaw=TURN_YAW, turn=turn, **window)[1]
                    cases.append(CloningCase(clip["path"], TURN_KIND, driver_track(driver, name=clip["path"]),
                                             turned.to_layout("body15")))  # fmt: skip
        if travelling:
            travelled = sum(c.kind == TRAVEL_KIND for c in cases)
            turn = (draw_turn(np.random.default_rng([TRAVEL_SEED, travelled]), frames) if travelled % 2 else None)
            wide = {**window, "size": picture_size(config, WIDE)}
            walked = render_performance(motion, ref_skeleton, ref_look, yaw=config.reference_yaw, turn=turn,
                                        **wide)[1]  # fmt: skip
            if travel(walked) >= TRAVEL_LEAST and stays_in_frame(config, walked):
                skeleton, look, _ = get_character(TRAVEL_CHARACTER)
                driver = render_performance(motion, skeleton, look, yaw=TRAVEL_YAW, turn=turn, **wide)[1]
                cases.append(CloningCase(clip["path"], TRAVEL_KIND, driver_track(driver, name=clip["path"]),
                                         walked.to_layout("body15"), WIDE))  # fmt: skip
        used += len(cases) > found
    if not cases:
        raise InputError(f"no clip of at least {CASE_START + frames} frames whose ground truth stays inside the frame")
    log.info("%d cloning cases from %d clips", len(cases), used)
    return cases


def network_drive(weights: str | Path | None, references: Mapping[str, PoseTrack], device: str = "cpu") -> Drive:
    """`clone drive --method retarget` with ``weights`` (None: the shipped ones) onto the reference of each case's
    picture (:func:`references`)."""
    from clone.drive.poses import finish_driven
    from retarget.api import load_retargeter

    net = load_retargeter(weights, device=device)
    codes = {picture: net.reference_codes(reference) for picture, reference in references.items()}

    def drive(case: CloningCase) -> PoseTrack:
        reference = references[case.picture]
        return finish_driven(net.retarget(case.driver, codes[case.picture]), case.driver, reference,
                             retargeted=True)[0]  # fmt: skip

    return drive


def global_scale_drive(references: Mapping[str, PoseTrack]) -> Drive:
    """`clone drive --method global-scale` (Everybody Dance Now's global scaling) onto the reference of each
    case's picture."""
    from clone.drive.poses import finish_driven, global_scale_to
    from retarget.baselines.global_scale import scale_stats

    targets = {picture: scale_stats(r.joints, r.joint_layout) for picture, r in references.items()}

    def drive(case: CloningCase) -> PoseTrack:
        reference = references[case.picture]
        scaled = global_scale_to(case.driver, targets[case.picture], reference.image_size)
        return finish_driven(scaled, case.driver, reference, retargeted=False)[0]

    return drive


# The demo's two pose measures (clone.metrics): summary key -> what cloning.md calls it.
MEASURES: dict[str, str] = {
    "pose_rmse_pct": "pose error (RMSE of the MidHip-aligned joints, % of the ground truth's height)",
    "root_rmse_pct": "placement (RMS distance of the MidHip from the truth's, % of its height)",
}


def case_errors(driven: PoseTrack, truth: PoseTrack) -> dict[str, float]:
    """The demo's pose error and placement of one case (:data:`MEASURES`)."""
    from clone.metrics import track_gt_scores

    summary = track_gt_scores(driven.to_layout(truth.layout), truth).summary
    return {key: float(summary[key]) for key in MEASURES}


def score(cases: Sequence[CloningCase], methods: Mapping[str, Drive],
          progress: Callable[[int, int], None] | None = None) -> dict[str, dict[str, np.ndarray]]:  # fmt: skip
    """Measure -> row -> [N] errors (% of height) of every case, in the order of ``cases``."""
    errors = {key: {name: np.empty(len(cases)) for name in methods} for key in MEASURES}
    for k, case in enumerate(cases):
        for name, drive in methods.items():
            for key, value in case_errors(drive(case), case.truth).items():
                errors[key][name][k] = value
        if progress is not None:
            progress(k + 1, len(cases))
    return errors


def summarise(cases: Sequence[CloningCase], errors: Mapping[str, Mapping[str, np.ndarray]], baseline: str) -> dict:
    """Per measure, row and pair kind the mean ± its standard error, and the paired difference to ``baseline``.

    ``all`` is the demo's own pairs: the turning and travelling drivers (:data:`TURN_KIND`, :data:`TRAVEL_KIND`)
    are kinds of their own, so that ``all`` reads the same with and without them."""
    kinds = list(dict.fromkeys(c.kind for c in cases))
    masks = {**{k: np.array([c.kind == k for c in cases]) for k in kinds},
             "all": np.array([c.kind not in (TURN_KIND, TRAVEL_KIND) for c in cases])}  # fmt: skip

    def stats(values: np.ndarray) -> dict[str, float]:
        mean, se = mean_se(values)
        return {"mean": mean, "se": se}

    measures = {}
    for key, rows in errors.items():
        measures[key] = {}
        for name, e in rows.items():
            measures[key][name] = {k: stats(e[m]) for k, m in masks.items()}
            measures[key][name]["vs_" + baseline] = {k: stats(e[m] - rows[baseline][m]) for k, m in masks.items()}
    return {"cases": len(cases), "clips": len({c.clip for c in cases}), "kinds": kinds, "measures": measures}


def markdown(doc: Mapping) -> str:
    """cloning.md: per measure a table (rows by method, pair kinds across) and the paired differences."""
    kinds = [*doc["kinds"], "all"]
    base = doc["baseline"]
    head = ["| method | " + " | ".join(kinds) + " |", "|---" * (len(kinds) + 1) + "|"]
    lines = ["# Cloning-kind evaluation", "",
             (f"{doc['cases']} cases from {doc['clips']} clips of the {doc['split']} split, {doc['frames']} frames "
              "each; mean ± standard error over the cases.")]  # fmt: skip
    for key, rows in doc["measures"].items():
        lines += ["", f"## {MEASURES[key][0].upper()}{MEASURES[key][1:]}", "", *head]
        for name, row in rows.items():
            lines.append(f"| {name} | " + " | ".join(f"{row[k]['mean']:.2f} ± {row[k]['se']:.2f}" for k in kinds)
                         + " |")  # fmt: skip
        lines += ["", f"Paired difference to {base} (negative: lower error):", "", *head]
        for name, row in rows.items():
            if name != base:
                diff = row["vs_" + base]
                lines.append(f"| {name} | " + " | ".join(f"{diff[k]['mean']:+.3f} ± {diff[k]['se']:.3f}"
                                                         for k in kinds) + " |")  # fmt: skip
    lines += ["", "## Notes", "",
              f"- Drivers: {doc['pairs']}. Reference: {doc['reference']}.",
              ("- Every method runs as `clone drive` runs it (networks: motion codes refined, foot skating cleaned "
               "with the driver's contacts; then started where the reference stands and kept inside the picture).")]  # fmt: skip
    return "\n".join(lines) + "\n"


__all__ = [
    "CASE_START", "DEMO", "MEASURES", "SQUARE", "TRAVEL_KIND", "TURN_KIND", "WIDE", "CloningCase", "case_errors",
    "cloning_cases", "global_scale_drive", "markdown", "network_drive", "picture_size", "references", "score",
    "summarise", "travel",
]
