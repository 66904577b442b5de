"""`clone retarget eval`'s library side: gather the rows, run every source of cases, write the folder."""

from __future__ import annotations

import json
import logging
import re
import time
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from pose_io.atomic import atomic_dir, check_new_output
from pose_io.errors import InputError
from pose_io.track import PoseTrack
from retarget.baselines.methods import global_scale_retarget, limb_scale_retarget
from retarget.evaluate.cases import ClipMotions, evaluate
from retarget.evaluate.codes import code_silhouettes, plot_codes, silhouette
from retarget.evaluate.config import DEFAULT_CONFIG, PROBE_ROW, EvalConfig, Method, Progress
from retarget.evaluate.real import real_pair_results
from retarget.evaluate.references3d import REFERENCES_3D
from retarget.evaluate.report import markdown_report, report_notes
from retarget.evaluate.turns import MotionSource
from retarget.world.split import WorldSplit

log = logging.getLogger(__name__)

BASELINES: dict[str, Method] = {
    "global scaling (EDN)": global_scale_retarget,
    "2D per-limb scaling (FK)": limb_scale_retarget,
}
# The authors' release: row name -> file in the --official folder.
OFFICIAL_FILES: dict[str, str] = {
    "authors' full": "pretrained_full.pth",
    "authors' skeleton-only": "pretrained_skeleton.pth",
    "authors' view-only": "pretrained_view.pth",
}
DESCRIPTIONS: dict[str, str] = {
    "ours": "our network; skeleton and view codes and placement from the reference window; the driver's motion "
    "code refined by gradient steps on its own reconstruction (retarget.inference.refine) unless the steps are 0",
    "global scaling (EDN)": "Everybody Dance Now's global pose normalisation: per-frame scale and offset "
    "interpolated between the near and far ankle positions of the driver and of the reference",
    "2D per-limb scaling (FK)": "naive 2D retargeting: every 2D limb of the driver scaled to the reference's "
    "2D limb length (95th percentile over the window), rebuilt from MidHip by forward kinematics, root path "
    "scaled by the leg ratio",
    **{name: "the authors' released weights (" + file + ")" for name, file in OFFICIAL_FILES.items()},
    **REFERENCES_3D,
}


def network_method(
    weights: str | Path, device: str = "cpu", refine_steps: int | None = None
) -> tuple[Method, object]:
    """A retargeting method backed by a checkpoint (ours or the authors'), and its ``Retargeter``.

    ``refine_steps``: motion-code refinement steps (None: inference's default, ``InferenceConfig``; 0: the
    network as its encoders give the codes, as the authors released their models).
    """
    from retarget.api import load_retargeter
    from retarget.inference.config import InferenceConfig

    config = InferenceConfig() if refine_steps is None else InferenceConfig(refine_steps=refine_steps)
    net = load_retargeter(weights, device=device, config=config, backend="torch")

    def run(motion: PoseTrack, reference: PoseTrack) -> PoseTrack:
        return net.retarget(motion, net.reference_codes(reference))

    return run, net


def _training_seed(path: Path) -> int | None:
    """The world seed a clone2d checkpoint was trained with, when it records one."""
    from retarget.network.checkpoint import load_weights

    training = load_weights(path).training or {}
    seed = training.get("config", {}).get("seed") if isinstance(training.get("config"), dict) else None
    return int(seed) if isinstance(seed, int) else None


@dataclass
class _Rows:
    """The rows of the tables: methods by name, the networks among them, what each row is, remarks for the notes."""

    methods: dict[str, Method] = field(default_factory=dict)
    nets: dict[str, object] = field(default_factory=dict)
    info: dict[str, dict[str, str]] = field(default_factory=dict)
    remarks: list[str] = field(default_factory=list)

    def add_network(
        self, name: str, path: Path, description: str, device: str, world_seed: int | None,
        refine_steps: int | None = None,
    ) -> None:  # fmt: skip
        if name in self.methods or name in BASELINES or name in REFERENCES_3D:
            raise InputError(f"--compare {name}: that row name is taken; choose another")
        self.methods[name], self.nets[name] = network_method(path, device, refine_steps)
        steps = self.nets[name].config.refine_steps
        self.info[name] = {"kind": "network", "description": description, "weights": str(path),
                           "refine_steps": str(steps)}  # fmt: skip
        trained = _training_seed(path)
        if world_seed is not None and trained is not None and trained != world_seed:
            self.remarks.append(f"Warning: {name} was trained on the world of seed {trained}, these cases come "
                                f"from the world of seed {world_seed}: its training motions may be among them "
                                "(--world-seed).")  # fmt: skip


def _gather_rows(
    weights: str | Path | None, compare: Mapping[str, str | Path], official: str | Path | None, device: str,
    world_seed: int | None, refine_steps: int | None = None,
) -> _Rows:  # fmt: skip
    """Networks (ours and ``compare`` refining ``refine_steps``, the authors' as released), then the 2D baselines,
    then the 3D references."""
    from retarget.api import PACKAGED_WEIGHTS

    rows = _Rows()
    if weights is None and PACKAGED_WEIGHTS.is_file():
        weights = PACKAGED_WEIGHTS
    if weights is not None:
        rows.add_network("ours", Path(weights), DESCRIPTIONS["ours"], device, world_seed, refine_steps)
    else:
        rows.remarks.append("ours: not evaluated (no --weights and no shipped weights).")
    for name, path in compare.items():
        rows.add_network(name, Path(path), "another checkpoint, run like ours", device, world_seed, refine_steps)
    if official is not None:
        found = {name: Path(official) / file for name, file in OFFICIAL_FILES.items()
                 if (Path(official) / file).is_file()}  # fmt: skip
        if not found:
            raise InputError(f"{official}: none of {', '.join(OFFICIAL_FILES.values())} is there")
        for name, path in found.items():
            rows.add_network(name, path, DESCRIPTIONS[name], device, world_seed, refine_steps=0)  # as released
    else:
        rows.remarks.append("authors' released model: not evaluated (no --official folder).")
    for name, method in BASELINES.items():
        rows.methods[name] = method
        rows.info[name] = {"kind": "2D baseline", "description": DESCRIPTIONS[name]}
    for name in REFERENCES_3D:
        rows.info[name] = {"kind": "3D reference", "description": DESCRIPTIONS[name]}
    return rows


def _case_sources(
    split: WorldSplit, bvh: Sequence[str | Path], config: EvalConfig, fps: float
) -> dict[str, MotionSource | None]:
    """Table title -> source of motions: the split's own windows (None), its turn cases (``config.turns``), then
    the extra mocap clips if any."""
    from retarget.evaluate.turns import TURN_DEGREES, TURN_RANGE, CapturedTurns, TurnedMotions
    from retarget.world.rigs import load_motion

    sources: dict[str, MotionSource | None] = {f"{split.name} split": None}
    if config.turns:
        lo, hi = TURN_RANGE
        sources[f"{split.name} split, turned {lo:g}-{hi:g}°"] = TurnedMotions(split, config.seed)
        captured = CapturedTurns(split, config.length)
        if captured.num_motions:
            sources[f"{split.name} split, captured turns over {TURN_DEGREES:g}° ({captured.num_motions} windows)"] = (
                captured
            )
    if bvh:
        clips = [load_motion(path, fps=fps) for path in bvh]
        sources[f"extra mocap ({len(clips)} clip{'s' if len(clips) > 1 else ''})"] = ClipMotions(
            clips, split.characters, config.length, max(1, config.length // 2)
        )
    return sources


def _slug(name: str) -> str:
    return re.sub(r"[^a-z0-9]+", "_", name.lower()).strip("_") or "method"


def _plot_files(names: Sequence[str]) -> dict[str, str]:
    """Network row -> its ``codes_<slug>.png``, made unique when two names give one slug."""
    files: dict[str, str] = {}
    for name in names:
        file = f"codes_{_slug(name)}.png"
        files[name] = file if file not in files.values() else f"codes_{_slug(name)}_{len(files)}.png"
    return files


def _document(
    split: WorldSplit, config: EvalConfig, bvh: Sequence[str | Path], rows: _Rows, results: dict,
    real_results: dict, silhouettes: dict[str, dict[str, float]], silhouette_errors: dict[str, dict[str, float]],
) -> dict:  # fmt: skip
    """The document of eval.json, with its notes and the names of the code plots (not yet its ``seconds``)."""
    doc: dict = {
        "config": asdict(config),
        "split": split.name,
        "world": {
            "motions": split.num_motions, "characters": list(split.character_names), "views": list(split.views),
            "canvas_size": list(split.canvas_size),
        },
        "extra_mocap": [str(p) for p in bvh],
        "methods": rows.info,
        "results": results,
        "real_pairs": real_results,
        "silhouettes": silhouettes,
        "silhouette_errors": silhouette_errors,
        "remarks": rows.remarks,
    }
    doc["notes"] = report_notes(doc)
    doc["code_plots"] = _plot_files([name for name in silhouettes if name in rows.nets])
    return doc


def _write(
    out: Path, overwrite: bool, doc: dict, plots: Mapping[str, tuple[dict, dict]], started: float
) -> str:
    """Write the code plots, eval.json and eval.md into ``out`` atomically; sets ``doc["seconds"]``."""
    with atomic_dir(out, overwrite=overwrite) as tmp:
        for name, (codes, labels) in plots.items():
            own = {k: silhouette(c, labels[k]) for k, c in codes.items()}  # the plotted grid's own scores
            plot_codes(tmp / doc["code_plots"][name], name, codes, labels, own)
        doc["seconds"] = round(time.perf_counter() - started, 1)
        table = markdown_report(doc)
        (tmp / "eval.json").write_text(json.dumps(doc, indent=2))
        (tmp / "eval.md").write_text(table)
    return table


def run_eval(
    split: WorldSplit,
    out: str | Path,
    *,
    weights: str | Path | None = None,
    compare: Mapping[str, str | Path] | None = None,
    official: str | Path | None = None,
    bvh: Sequence[str | Path] = (),
    real: Mapping[str, PoseTrack] | None = None,
    config: EvalConfig = DEFAULT_CONFIG,
    fps: float = 30.0,
    device: str = "cpu",
    overwrite: bool = False,
    world_seed: int | None = None,
    refine_steps: int | None = None,
    probe_split: WorldSplit | None = None,
    progress: Progress | None = None,
) -> tuple[dict, str]:
    """Evaluate every method; write ``eval.json``, ``eval.md`` and ``codes_<network>.png`` into ``out`` atomically.

    Args:
        split: the world split the cases, characters and references come from.
        out: output folder (must not exist unless ``overwrite``).
        weights: our checkpoint; None = the shipped weights when present (otherwise no "ours" row).
        compare: more checkpoints, row name -> path (e.g. ablations).
        official: folder with the authors' ``pretrained_{full,skeleton,view}.pth`` and statistics; a row for
            each file found.
        bvh: extra mocap files, replayed on the split's characters as a second source of cases.
        real: real tracks by name; every ordered pair is retargeted by every network and baseline and
            measured without ground truth (:mod:`retarget.evaluate.real`).
        config: what is evaluated.
        fps: the world's frame rate.
        device: where the networks run.
        overwrite: replace an existing ``out``.
        world_seed: the seed ``split``'s world was built with; a checkpoint trained on another world's split
            (its recorded training seed differs) gets a warning in the notes, as its training motions may be
            among the cases.
        refine_steps: motion-code refinement steps of ours and ``compare`` (None: inference's default); the
            authors' models run without refinement, as released.
        probe_split: the split a proportion probe learns from (the training split) when ``config.probe_steps``
            is above 0; its silhouettes join the networks' as the row :data:`~retarget.evaluate.config.PROBE_ROW`,
            its inputs prepared as the first network row's.
        progress: ``progress(done, total)`` over all cases and silhouette grids.

    Returns:
        ``(document written to eval.json, markdown of eval.md)``.

    Raises:
        InputError: an existing ``out``, unreadable weights or mocap, a clash of row names, an ``official``
            folder without any of the authors' weights, or a split too small to evaluate.
    """
    started = time.perf_counter()
    out = Path(out)
    check_new_output(out, overwrite)
    rows = _gather_rows(weights, compare or {}, official, device, world_seed, refine_steps)
    sources = _case_sources(split, bvh, config, fps)
    probing = config.probe_steps > 0 and probe_split is not None and bool(rows.nets)
    total = config.pairs * len(sources) + len(rows.nets) + int(probing)
    done = 0

    def tick(step: int, _: int) -> None:
        if progress is not None:
            progress(done + step, total)

    results = {}
    for source_name, motions in sources.items():
        results[source_name] = evaluate(split, rows.methods, config, motions, fps, tick)
        done += config.pairs
    measured = {n: m for n, m in rows.methods.items() if n in rows.nets or n in BASELINES}
    real_results = real_pair_results(real, measured) if real else {}
    silhouettes: dict[str, dict[str, float]] = {}
    silhouette_errors: dict[str, dict[str, float]] = {}
    plots: dict[str, tuple[dict[str, np.ndarray], dict[str, np.ndarray]]] = {}
    for name, net in rows.nets.items():
        scores, errors, codes, labels = code_silhouettes(net, split, config, fps)
        silhouettes[name], silhouette_errors[name] = scores, errors
        plots[name] = (codes, labels)
        done += 1
        tick(0, total)
    if probing:
        from retarget.evaluate.probe import ProbeConfig, probe_silhouettes, train_probe

        first = next(iter(rows.nets.values()))
        probe = train_probe(probe_split, first, ProbeConfig(steps=config.probe_steps, seed=config.seed), fps)
        silhouettes[PROBE_ROW], silhouette_errors[PROBE_ROW] = probe_silhouettes(probe, first, split, config, fps)
        done += 1
        tick(0, total)
    elif config.probe_steps > 0:
        rows.remarks.append("proportion probe: not trained (no network row to share its preprocessing, or no "
                            "training split given).")
    doc = _document(split, config, bvh, rows, results, real_results, silhouettes, silhouette_errors)
    table = _write(out, overwrite, doc, plots, started)
    log.info("evaluation written to %s in %.0f s", out, doc["seconds"])
    return doc, table
