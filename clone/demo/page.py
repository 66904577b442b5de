"""The demo's overview page: what was rendered and trained, then ``clone.report.overview`` over the pairs."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from clone.demo.config import DemoConfig, PairConfig
from clone.report.overview import read_section, write_overview

OVERVIEW = "report.html"

_NOTES = (
    (
        "Pose error is the primary measure: the joints' RMS distance from the ground truth after subtracting each "
        "frame's MidHip from both (so where the body stands does not count), in % of the reference's height, "
        "as `clone retarget eval` measures it; the ratio row says how many times global scaling's error is "
        "retargeting's. Placement is where the body stands (the MidHip's RMS distance). The better value of each "
        "pair is highlighted."
    ),
    (
        "Faces the true side checks the view: a body seen from its left faces image-left, its nose left of its "
        "neck, and from its right the other way, so the sign of the nose's offset from the neck tells which side "
        "the camera sees (the shoulders' left-right order cannot: it is the same for every view within 90° of the "
        "front). It is the share of frames in which the output faces the same way as the ground truth, counting "
        "frames where the ground truth's offset is at least 1 % of its height."
    ),
    (
        "SSIM and PSNR compare the generated frames with the true ones, whole and in a crop around the true "
        "person; the crop is where the claims show. Moved onto the stage: the share of frames that were off the "
        "part of the frame the reference used, so the track was shifted onto it (clone.drive.stage)."
    ),
)


def _motion_text(motions: Mapping[str, Any], key: str, start: int, frames: int | None) -> str:
    motion = motions[key]
    stop = motion.num_frames if frames is None else start + frames
    return f"{motion.name}, frames {start}-{stop - 1} of {motion.num_frames} at {motion.fps:g} fps"


def _character_text(name: str) -> str:
    from clone.synth import get_character

    skeleton, _, _ = get_character(name)
    return f"{name} ({skeleton.height:.2f} m)"


def _pair_details(config: DemoConfig, pair: PairConfig, motions: Mapping[str, Any],
                  edge_px: float) -> tuple[tuple[str, str], ...]:  # fmt: skip
    motion = _motion_text(motions, pair.motion, pair.start, pair.frames)
    size = config.render_size
    truth = (f"{_character_text(config.reference_character)} performing the same frames, seen by the "
             f"reference's camera ({config.reference_yaw:+g}°)")
    inside = (f"every ground-truth joint stays at least {edge_px:.0f} px inside the {size}² frame (required: "
              f"{config.edge_margin * size:.0f} px)")
    return (
        ("Driver", f"{_character_text(pair.character)}, camera {pair.yaw:+g}°: {motion}"),
        ("Ground truth", truth),
        ("Inside the frame", inside),
    )  # fmt: skip


def write_demo_page(
    out: Path,
    config: DemoConfig,
    motions: Mapping[str, Any],
    edge_px: Mapping[str, float],
    seconds: Mapping[str, float],
    trained: Any,
    device: str,
) -> Path:
    """Write ``out/report.html`` over the pairs' report folders ``out/<pair>/report``.

    Args:
        out: the demo folder.
        config: what the demo ran.
        motions: the built-in motions (``clone.demo.scenes.demo_motions``).
        edge_px: pair -> its ground truth's distance from the frame's edges in pixels.
        seconds: stage -> wall time so far.
        trained: the ``clone.train_ref.TrainResult`` of the reference model.
        device: where it ran.

    Returns:
        The page's path.
    """
    import torch

    sections = [
        read_section(p.name, p.title, _pair_details(config, p, motions, edge_px[p.name]), out / p.name / "report", out)
        for p in config.pairs
    ]
    ref_motion = _motion_text(motions, config.reference_motion, 0, config.reference_frames)
    times = ", ".join(f"{k} {v:.0f} s" for k, v in seconds.items())
    n = torch.get_num_threads()
    threads = f", {n} CPU thread{'s' if n > 1 else ''}" if device == "cpu" else ""
    reference = (f"{_character_text(config.reference_character)}, camera {config.reference_yaw:+g}°: {ref_motion} "
                 "(reference/)")
    model = (f"ref_model.pt: {config.model_size}² canvas, {trained.steps} training steps in "
             f"{trained.seconds / 60:.1f} min on {device}{threads}")
    frames = (f"{config.render_size}² videos; a ground truth per pair: the reference's character performing the "
              "driver's motion, seen by the reference's camera")
    intro = (
        ("Reference", reference),
        ("Reference model", model),
        ("Frames", frames),
        ("Stage times", f"{times} (the overview itself not counted)"),
    )
    return write_overview(out / OVERVIEW, "clone2d demo: performance cloning, pair by pair", intro, sections,
                          _NOTES)  # fmt: skip
