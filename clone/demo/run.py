"""`clone demo` end to end: render the scenes, train the reference model once, report every pair, compose.

Layout of a demo folder (``--out``, default ``demo_out``)::

    report.html              the overview: summary across pairs, then each pair's section, video and stills
    demo.json                the configuration, stage times, in-frame checks and every pair's summary
    reference/               the reference video (frames/, poses/, poses.npz, meta.json)
    ref_model.pt             the reference model trained on it
    <pair>/driver/           the driver's video
    <pair>/ground_truth/     the reference's character performing the driver's motion, the reference's camera
    <pair>/report/           `clone report` of the pair (report.html, side_by_side.mp4, stills, metrics.json)
    .clone2d-demo            marker: `clone demo` may replace this folder
"""

from __future__ import annotations

import json
import logging
import os
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path

from clone.demo.config import DemoConfig
from clone.demo.folder import check_out, finish_out, prepare_out
from clone.demo.scenes import demo_motions, render_scenes
from pose_io.atomic import atomic_file

log = logging.getLogger(__name__)

StageFn = Callable[[str], None]
RECORD = "demo.json"


@dataclass(frozen=True)
class DemoResult:
    """What a demo run wrote and measured.

    Attributes:
        out: the demo folder.
        report: the overview page.
        model: the reference model.
        seconds: stage -> wall time (``render``, ``train``, ``report <pair>``..., ``overview``).
        summary: pair -> method -> measure -> value (each pair's report summary).
        edge_px: pair -> how close its ground truth comes to the frame's edges, in pixels.
        steps: training steps the reference model got.
    """

    out: Path
    report: Path
    model: Path
    seconds: dict[str, float]
    summary: dict[str, dict[str, dict[str, float]]]
    edge_px: dict[str, float]
    steps: int


def run_demo(
    out: str | os.PathLike = "demo_out",
    config: DemoConfig | None = None,
    device: str = "cpu",
    weights: str | os.PathLike | None = None,
    stage: StageFn | None = None,
    grow_threads: bool = False,
) -> DemoResult:
    """Render the scenes, train the reference model, report every pair and write the overview.

    Args:
        out: output folder (replaced when an earlier demo made it).
        config: sizes, budget and pairs (default: ``DemoConfig()``, the shipped demo).
        device: torch device for training and driving.
        weights: retargeting weights (default: the ones shipped in the package).
        stage: called with a short description as each stage starts.
        grow_threads: raise torch's threads while training when cores come free (`clone demo` without
            ``--threads``; see :func:`clone.train_ref.train_reference`).

    Returns:
        Where everything went, stage times in seconds and every pair's summary.
    """
    say = stage or (lambda text: log.info(text))
    config = config or DemoConfig()
    out = Path(out)
    check_out(out)
    if weights is not None:  # a bad --weights fails before the earlier demo is touched
        from retarget.api import load_retargeter

        load_retargeter(weights, device)
    old = prepare_out(out)
    ok = False
    try:
        result = _run(out, config, device, weights, say, grow_threads)
        ok = True
    finally:
        finish_out(out, old, ok)
    return result


def _run(out: Path, config: DemoConfig, device: str, weights: str | os.PathLike | None,
         say: StageFn, grow_threads: bool = False) -> DemoResult:  # fmt: skip
    """The demo's stages into the prepared folder ``out``."""
    from clone.demo.page import write_demo_page  # the report and training packages load only when a demo runs
    from clone.report import make_report
    from clone.train_ref import TrainConfig, train_reference

    seconds: dict[str, float] = {}
    start = time.perf_counter()
    edge_px = render_scenes(out, config, say)
    seconds["render"] = time.perf_counter() - start

    say(f"training the reference model ({config.minutes:g} min at {config.model_size}px)")
    start = time.perf_counter()
    model = out / "ref_model.pt"
    trained = train_reference(
        out / "reference" / "poses.npz", out / "reference" / "frames", model,
        config=TrainConfig(size=config.model_size, seed=config.seed),
        minutes=config.minutes, device=device, weights=weights, grow_threads=grow_threads,
    )  # fmt: skip
    seconds["train"] = time.perf_counter() - start

    summary = {}
    for pair in config.pairs:
        say(f"{pair.name}: driving the model with both methods and writing its report")
        start = time.perf_counter()
        folder = out / pair.name
        run = make_report(
            folder / "driver" / "poses.npz", folder / "report", model_path=model,
            gt_poses=folder / "ground_truth" / "poses.npz", gt_frames=folder / "ground_truth" / "frames",
            device=device, weights=weights,
        )  # fmt: skip
        summary[pair.name] = run.summary
        seconds[f"report {pair.name}"] = time.perf_counter() - start

    say("writing the overview page")
    start = time.perf_counter()
    page = write_demo_page(out, config, demo_motions(), edge_px, seconds, trained, device)
    seconds["overview"] = time.perf_counter() - start
    _write_record(out / RECORD, config, seconds, edge_px, summary, trained.steps, device)
    return DemoResult(out, page, model, seconds, summary, edge_px, trained.steps)


def _write_record(path: Path, config: DemoConfig, seconds: dict[str, float], edge_px: dict[str, float],
                  summary: dict, steps: int, device: str) -> None:  # fmt: skip
    """demo.json: everything the demo measured, as strict JSON."""
    from clone.report.document import json_value

    record = {"config": asdict(config), "device": device, "training_steps": steps, "seconds": seconds,
              "ground_truth_edge_px": edge_px, "pairs": summary}  # fmt: skip
    with atomic_file(path) as tmp:
        tmp.write_text(json.dumps(json_value(record), indent=1, allow_nan=False) + "\n", encoding="utf-8")
