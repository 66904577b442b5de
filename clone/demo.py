"""`clone demo`: the whole pipeline on a built-in synthetic example with ground truth.

The motion world renders three performances from the two motions shipped in ``clone/data``:

- the reference: a tall, long-legged character dancing, seen slightly from its right (the video a user would
  film of their target person);
- the driver: a short, stocky character dancing another take, seen from its left (the video of the person whose
  motion we want);
- the ground truth: the reference character performing the driver's motion, seen by the reference's camera
  (what a perfect cloning run would produce; no real video has it).

Then it trains a reference model on the reference video and writes a report that drives it with both
retargeting and Everybody Dance Now's global scaling and measures both against the ground truth.
"""

from __future__ import annotations

import logging
import os
import shutil
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from importlib import resources
from pathlib import Path

import numpy as np

from pose_io.errors import InputError

log = logging.getLogger(__name__)

MARKER = ".clone2d-demo"

StageFn = Callable[[str], None]


@dataclass(frozen=True)
class DemoConfig:
    """Sizes and budgets of a demo run.

    Attributes:
        render_size: side of the rendered videos in pixels.
        model_size: canvas of the pose-to-frame generator.
        reference_frames: frames of the reference video (None: the whole motion, 458).
        driver_frames: frames of the driver video (None: the whole motion, 215).
        minutes: CPU training budget of the reference model.
        reference_character / driver_character: named characters of the motion world.
        reference_yaw / driver_yaw: camera yaw in degrees relative to each performer's mean facing.
        seed: training seed.
    """

    render_size: int = 256
    model_size: int = 128
    reference_frames: int | None = None
    driver_frames: int | None = None
    minutes: float = 6.0
    reference_character: str = "tall_long_legs"
    driver_character: str = "short_stocky"
    reference_yaw: float = 15.0
    driver_yaw: float = -35.0
    seed: int = 0


QUICK = DemoConfig(render_size=192, model_size=64, reference_frames=300, driver_frames=120, minutes=1.2)


@dataclass(frozen=True)
class DemoResult:
    out: Path
    report: Path
    model: Path
    seconds: dict[str, float]
    summary: dict[str, dict[str, float]]


def demo_motions() -> dict[str, object]:
    """The two shipped motions as ``Motion3D`` (reference, driver)."""
    from retarget.world import Motion3D

    with resources.as_file(resources.files("clone") / "data" / "demo_motions.npz") as path:
        data = np.load(path)
        fps = float(data["fps"])
        return {
            role: Motion3D(positions=data[role].astype(np.float32), fps=fps, name=str(data[f"{role}_name"]),
                           source=f"clone2d built-in demo ({role})")
            for role in ("reference", "driver")
        }


def check_out(out: Path) -> None:
    """Raise InputError unless ``out`` is new or a folder an earlier demo made, in a writable place."""
    from clone.outputs import check_writable_folder

    if out.exists() and not (out / MARKER).is_file():
        raise InputError(f"{out}: exists and was not made by `clone demo`; choose another --out")
    check_writable_folder(out.parent, f"--out {out}")


def prepare_out(out: Path) -> Path | None:
    """Make ``out`` ready; an earlier demo's folder is moved aside (returned) and only deleted once the new run
    has finished (:func:`finish_out`), or put back when it fails."""
    check_out(out)
    old = None
    if out.exists():
        old = out.with_name(f".{out.name}.old-{os.getpid()}")
        os.replace(out, old)
    out.mkdir(parents=True)
    (out / MARKER).write_text("made by clone demo; `clone demo` replaces this folder\n")
    return old


def finish_out(out: Path, old: Path | None, ok: bool) -> None:
    """Drop the earlier demo (``ok``) or the half-made new one, whose place the earlier demo takes again."""
    if ok:
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
        return
    shutil.rmtree(out, ignore_errors=True)
    if old is not None:
        os.replace(old, out)


def run_demo(
    out: str | os.PathLike = "demo_out",
    config: DemoConfig = DemoConfig(),
    device: str = "cpu",
    weights: str | os.PathLike | None = None,
    stage: StageFn | None = None,
) -> DemoResult:
    """Render the example, train the reference model, write the report.

    Args:
        out: output folder (replaced when an earlier demo made it).
        config: sizes and budget.
        device: torch device for training and driving.
        weights: retargeting weights (default: the ones shipped in the package).
        stage: called with a short description as each stage starts.

    Returns:
        Where everything went, stage times in seconds, and the report's per-method summary.
    """
    say = stage or (lambda text: log.info(text))
    out = Path(out)
    check_out(out)
    if weights is not None:  # a bad --weights fails before the earlier demo is touched
        from retarget.api import load_retargeter

        load_retargeter(weights, device)
    old = prepare_out(out)
    ok = False
    try:
        result = _run(out, config, device, weights, say)
        ok = True
    finally:
        finish_out(out, old, ok)
    return result


def _run(out: Path, config: DemoConfig, device: str, weights: str | os.PathLike | None,
         say: StageFn) -> DemoResult:
    """The demo's stages into the prepared folder ``out``."""
    from clone.report import make_report
    from clone.synth import get_character, save_performance
    from clone.train_ref import TrainConfig, train_reference

    motions = demo_motions()
    ref_skeleton, ref_look, _ = get_character(config.reference_character)
    drv_skeleton, drv_look, _ = get_character(config.driver_character)
    seconds: dict[str, float] = {}

    def performance(name: str, motion_role: str, skeleton, look, yaw: float, frames: int | None) -> Path:
        say(f"rendering the {name.replace('_', ' ')}")
        folder = out / name
        save_performance(
            folder, motions[motion_role], skeleton, look, yaw=yaw, size=config.render_size, frames=frames,
            extra_meta={"demo": {"role": name, "config": asdict(config)}},
        )
        return folder

    start = time.perf_counter()
    reference = performance("reference", "reference", ref_skeleton, ref_look, config.reference_yaw,
                            config.reference_frames)
    driver = performance("driver", "driver", drv_skeleton, drv_look, config.driver_yaw, config.driver_frames)
    truth = performance("ground_truth", "driver", ref_skeleton, ref_look, config.reference_yaw,
                        config.driver_frames)
    seconds["render"] = time.perf_counter() - start

    say(f"training the reference model ({config.minutes:g} min at {config.model_size}px)")
    start = time.perf_counter()
    model = out / "ref_model.pt"
    train_reference(
        reference / "poses.npz", reference / "frames", model,
        config=TrainConfig(size=config.model_size, seed=config.seed),
        minutes=config.minutes, device=device, weights=weights,
    )
    seconds["train"] = time.perf_counter() - start

    say("driving the model with both methods and writing the report")
    start = time.perf_counter()
    run = make_report(
        driver / "poses.npz", out / "report", model_path=model, gt_poses=truth / "poses.npz",
        gt_frames=truth / "frames", device=device, weights=weights,
    )
    seconds["report"] = time.perf_counter() - start
    return DemoResult(out=out, report=run.page, model=model, seconds=seconds, summary=run.summary)
