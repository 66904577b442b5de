"""The report of a `clone report` run: one folder with a self-contained page, its video, plots and numbers.

Layout of a report folder (all links in the page are relative, so the folder can be moved or zipped)::

    report.html          the page (inline CSS, no scripts, no network)
    side_by_side.mp4     driver | global scaling | retargeted | ground truth (written by the caller)
    metrics.json         per method: summary numbers, per-frame curves, details
    curves.png           per-frame curves of every measure, one line per method
    summary.png          one bar chart per summary measure
    still_<frame>.png    a few frames side by side with the skeletons drawn over them
    .clone2d-report      marker: this folder was made by a report and may be replaced with --overwrite

The folder is built in a temporary sibling and renamed into place, so a failed run leaves nothing behind.
An existing folder is replaced only when it carries the marker and the caller passes ``overwrite``.
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import html
import json
import logging
import math
import os
import shutil
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import cv2
import numpy as np

from clone.metrics import (
    METRICS,
    FrameScorer,
    Scores,
    evaluate_track,
)
from pose_io.atomic import atomic_dir
from pose_io.draw import blank_canvas, draw_pose
from pose_io.errors import InputError
from pose_io.layouts import get_layout
from pose_io.measures import reference_limb_lengths, skeleton_height
from pose_io.track import PoseTrack

if TYPE_CHECKING:
    from pose_io.video import Frames

log = logging.getLogger(__name__)

MARKER = ".clone2d-report"
PAGE = "report.html"
VIDEO = "side_by_side.mp4"
METRICS_FILE = "metrics.json"
CURVES = "curves.png"
SUMMARY = "summary.png"
METRICS_FORMAT = "clone2d-report-metrics"
METRICS_VERSION = 1

# One colour per column of the report (driver, then the methods in order, then the ground truth).
_PALETTE = ("#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#e377c2")


@dataclass(frozen=True, eq=False)
class MethodResult:
    """One way of driving the reference, as a report shows it.

    Attributes:
        label: column title, e.g. ``"Retargeted"``.
        poses: the driven poses, in the same image as the reference's poses.
        scores: its measures (``clone.metrics``).
        stills: frame index -> [H, W, 3] uint8 RGB generated frame, for the still images.
        still_poses: frame index -> [J, 2] the driven pose in that frame's pixels (drawn over the still),
            in ``poses.layout``; missing indices are drawn without a skeleton.
        description: one sentence on how the method works, shown on the page.
    """

    label: str
    poses: PoseTrack
    scores: Scores
    stills: Mapping[int, np.ndarray] = field(default_factory=dict)
    still_poses: Mapping[int, np.ndarray] = field(default_factory=dict)
    description: str = ""


@dataclass(frozen=True, eq=False)
class DriverInfo:
    """What drove the reference.

    Attributes:
        poses: the driver's pose track.
        source: where it was read from, as the user gave it.
        reference: the reference model, as the user gave it.
        scores: the driver's own measures (its own height and limb lengths), shown as a grey baseline column.
    """

    poses: PoseTrack
    source: str
    reference: str
    scores: Scores | None = None


@dataclass(frozen=True, eq=False)
class GroundTruth:
    """The reference really performing the driver's motion, when it exists.

    Attributes:
        poses_source: where its poses were read from, or None.
        frames_source: where its frames were read from, or None.
        stills: frame index -> [H, W, 3] uint8 RGB true frame, in the generated frames' pixels.
        still_poses: frame index -> [J, 2] true pose in those pixels.
        layout: layout of ``still_poses``.
    """

    poses_source: str | None = None
    frames_source: str | None = None
    stills: Mapping[int, np.ndarray] = field(default_factory=dict)
    still_poses: Mapping[int, np.ndarray] = field(default_factory=dict)
    layout: str = "body15"


# ------------------------------------------------------------------------------------------ output folder


def check_report_dir(out_dir: Path, overwrite: bool) -> None:
    """Raise InputError unless a report may be written to ``out_dir``.

    A new path is fine; an existing report folder (with the marker) only with ``overwrite``; anything else
    that exists (a file, a folder not made by a report) never.
    """
    if not out_dir.exists() and not out_dir.is_symlink():
        return
    if not out_dir.is_dir() or out_dir.is_symlink():
        raise InputError(f"{out_dir}: exists and is not a report folder; choose another --out")
    if not (out_dir / MARKER).is_file():
        raise InputError(
            f"{out_dir}: exists and was not made by `clone report` (no {MARKER}); choose another --out"
        )
    if not overwrite:
        raise InputError(f"{out_dir}: report already exists; pass --overwrite to replace it")


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def report_dir(out_dir: str | os.PathLike, overwrite: bool = False) -> Iterator[Path]:
    """Yield an empty temporary folder that becomes ``out_dir`` (marker included) when the block succeeds.

    Raises:
        InputError: before anything is written, when ``check_report_dir`` refuses ``out_dir``.
    """
    out_dir = Path(out_dir)
    check_report_dir(out_dir, overwrite)
    with atomic_dir(out_dir, overwrite=True) as stage:
        stage.chmod(0o777 & ~_umask())  # mkdtemp makes it private; a report is meant to be shared
        yield stage
        (stage / MARKER).write_text(
            "made by clone report; `clone report --overwrite` may replace this folder\n"
        )


# ----------------------------------------------------------------------------------------------- panels


def pose_panel(joints: np.ndarray, layout: str, image_size: tuple[int, int], height: int) -> np.ndarray:
    """A pose drawn on black, the image scaled to ``height`` rows.

    Args:
        joints: [J, 2] pixel coordinates in an image of ``image_size`` (width, height), NaN where missing.
        layout: their joint layout.
        image_size: (width, height) of that image.
        height: output rows.

    Returns:
        [height, round(width * height / image height), 3] uint8 RGB.
    """
    w, h = image_size
    k = height / h
    canvas = blank_canvas(max(1, round(w * k)), height)
    return draw_pose(canvas, np.asarray(joints, dtype=np.float64) * k, get_layout(layout))


def overlay(frame: np.ndarray, joints: np.ndarray | None, layout: str) -> np.ndarray:
    """A copy of ``frame`` ([H, W, 3] uint8 RGB) with the [J, 2] pose drawn thinly over it (None: no pose)."""
    out = np.array(frame, dtype=np.uint8, order="C", copy=True)  # generator frames may be strided views
    if joints is not None:
        draw_pose(out, joints, get_layout(layout), thickness=max(1, round(min(out.shape[:2]) / 256)))
    return out


def caption_height(height: int) -> int:
    """Rows of the caption strip above panels ``height`` rows tall."""
    return max(22, round(0.1 * height))


def side_by_side(panels: Sequence[np.ndarray], labels: Sequence[str], height: int) -> np.ndarray:
    """Panels next to each other at one height, each under a caption strip.

    Args:
        panels: [H_i, W_i, 3] uint8 RGB images; each is resized to ``height`` rows keeping its aspect.
        labels: one caption per panel.
        height: rows of the image part.

    Returns:
        [height + caption, sum of widths, 3] uint8 RGB, width and height even (H.264 needs them even).
    """
    if len(panels) != len(labels) or not panels:
        raise ValueError(f"side_by_side: {len(panels)} panels for {len(labels)} labels")
    bar_height = caption_height(height)
    scale = bar_height / 46  # Hershey simplex at 1.0 is ~22 px tall: text fills about half the strip
    columns = []
    for panel, label in zip(panels, labels):
        h, w = panel.shape[:2]
        width = max(1, round(w * height / h))
        if (w, h) != (width, height):
            interp = cv2.INTER_AREA if h > height else cv2.INTER_LINEAR
            panel = cv2.resize(panel, (width, height), interpolation=interp)
        bar = np.full((bar_height, width, 3), 32, dtype=np.uint8)
        (tw, th), _ = cv2.getTextSize(label, cv2.FONT_HERSHEY_SIMPLEX, scale, 1)
        org = (max(4, (width - tw) // 2), (bar_height + th) // 2)
        cv2.putText(bar, label, org, cv2.FONT_HERSHEY_SIMPLEX, scale, (235, 235, 235), 1, cv2.LINE_AA)
        columns.append(np.vstack([bar, panel]))
    out = np.hstack(columns)  # [caption + height, sum W_i, 3]
    h, w = out.shape[:2]
    return np.pad(out, ((0, h % 2), (0, w % 2), (0, 0)))


def still_indices(num_frames: int, count: int = 4) -> list[int]:
    """``count`` frame indices spread evenly inside ``range(num_frames)``, away from the ends."""
    if num_frames <= 0:
        return []
    count = min(count, num_frames)
    return sorted({round((i + 1) * num_frames / (count + 1) - 0.5) for i in range(count)})


# ------------------------------------------------------------------------------------------------ numbers


def _json_value(value: object) -> object:
    """Plain JSON: arrays to lists, NaN to null, +-inf to the strings "inf" / "-inf"."""
    if isinstance(value, Mapping):
        return {str(k): _json_value(v) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        return [_json_value(v) for v in value.tolist()]
    if isinstance(value, (list, tuple)):
        return [_json_value(v) for v in value]
    if isinstance(value, (float, np.floating)):
        value = float(value)
        if math.isnan(value):
            return None
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return value
    if isinstance(value, np.integer):
        return int(value)
    return value


def _scores_json(scores: Scores) -> dict[str, object]:
    return {"summary": scores.summary, "per_frame": scores.per_frame, "details": scores.details}


def metrics_document(
    methods: Mapping[str, MethodResult], driver: DriverInfo, gt: GroundTruth | None
) -> dict[str, object]:
    """The content of metrics.json, JSON-ready (NaN -> null, inf -> "inf")."""
    track = driver.poses
    doc = {
        "format": METRICS_FORMAT,
        "version": METRICS_VERSION,
        "notes": (
            "per_frame arrays have one value per driver frame; null = no value in that frame (e.g. no ankle in "
            "contact); \"inf\" = infinite (PSNR of identical frames). Units: see 'metrics'."
        ),
        "driver": {
            "source": driver.source,
            "frames": track.num_frames,
            "fps": track.fps,
            "image_size": list(track.image_size),
            "layout": track.layout,
        },
        "reference": driver.reference,
        "ground_truth": None if gt is None else {"poses": gt.poses_source, "frames": gt.frames_source},
        "metrics": {
            k: {
                "label": m.label,
                "unit": m.unit,
                "better": m.better,
                "display_scale": m.scale,
                "meaning": m.meaning,
            }
            for k, m in METRICS.items()
        },
        "methods": {
            name: {"label": m.label, "layout": m.poses.layout, **_scores_json(m.scores)}
            for name, m in methods.items()
        },
        "driver_baseline": None if driver.scores is None else _scores_json(driver.scores),
    }
    return _json_value(doc)  # type: ignore[return-value]


def _fmt(value: float, scale: float = 1.0) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "–"
    if math.isinf(value):
        return "∞" if value > 0 else "−∞"
    v = value * scale
    if abs(v) >= 100:
        return f"{v:.1f}"
    return f"{v:.3g}" if abs(v) >= 0.001 or v == 0 else f"{v:.2e}"


def best_methods(methods: Mapping[str, MethodResult], key: str) -> set[str]:
    """The methods with the better value of summary ``key`` (empty when all are equal, none has one, or the
    measure has no better direction)."""
    better = METRICS[key].better
    if better is None:
        return set()
    values = {n: m.scores.summary.get(key, float("nan")) for n, m in methods.items()}
    values = {n: v for n, v in values.items() if not math.isnan(v)}
    if len(values) < 2 or len(set(values.values())) == 1:
        return set()
    target = min(values.values()) if better == "lower" else max(values.values())
    return {n for n, v in values.items() if v == target}


# -------------------------------------------------------------------------------------------------- plots


def _colors(methods: Mapping[str, MethodResult]) -> dict[str, str]:
    return {name: _PALETTE[(i + 1) % len(_PALETTE)] for i, name in enumerate(methods)}


def plot_curves(path: Path, methods: Mapping[str, MethodResult], fps: float) -> list[str]:
    """Per-frame curves of every measure (one panel each, two columns, one line per method) as a PNG.

    Returns:
        The measures plotted, in order (none: no file written).
    """
    keys = [k for k in METRICS if any(k in m.scores.per_frame for m in methods.values())]
    if not keys:
        return []
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    colors = _colors(methods)
    cols = 2 if len(keys) > 1 else 1
    rows = math.ceil(len(keys) / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(11, 2.0 * rows + 0.5), sharex=True, squeeze=False)
    for ax in axes.flat[len(keys) :]:
        ax.axis("off")
    for ax, key in zip(axes.flat, keys):
        info = METRICS[key]
        for name, m in methods.items():
            if key not in m.scores.per_frame:
                continue
            y = np.asarray(m.scores.per_frame[key], dtype=np.float64) * info.scale
            y = np.where(np.isinf(y), np.nan, y)  # identical frames have no finite PSNR to draw
            t = np.arange(len(y)) / fps
            ax.plot(t, y, color=colors[name], lw=1.1, label=m.label, marker="." if len(y) < 60 else None)
        ax.set_title(f"{info.label} ({info.unit})" if info.unit else info.label, fontsize=9)
        ax.tick_params(labelsize=8)
        ax.grid(alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("time (s)", fontsize=8)
        ax.xaxis.set_tick_params(labelbottom=True)
    handles, labels = axes.flat[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="upper center", ncol=len(labels), fontsize=9, frameon=False)
    fig.tight_layout(rect=(0, 0, 1, 1 - 0.35 / fig.get_figheight()))
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return keys


def plot_summary(path: Path, methods: Mapping[str, MethodResult]) -> list[str]:
    """One small bar chart per summary measure (one bar per method) as a PNG.

    Returns:
        The measures plotted, in order.
    """
    keys = [k for k in METRICS if any(k in m.scores.summary for m in methods.values())]
    if not keys:
        return []
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    colors = _colors(methods)
    cols = min(4, len(keys))
    rows = math.ceil(len(keys) / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(11, 2.3 * rows + 0.3), squeeze=False)
    for ax in axes.flat[len(keys) :]:
        ax.axis("off")
    for ax, key in zip(axes.flat, keys):
        info = METRICS[key]
        names = [n for n, m in methods.items() if key in m.scores.summary]
        values = [methods[n].scores.summary[key] * info.scale for n in names]
        finite = [v for v in values if math.isfinite(v)]
        top = max(finite) if finite else 1.0
        drawn = [top * 1.1 if math.isinf(v) else (0.0 if math.isnan(v) else v) for v in values]
        bars = ax.bar(range(len(names)), drawn, color=[colors[n] for n in names])
        for bar, v in zip(bars, values):
            ax.annotate(_fmt(v), (bar.get_x() + bar.get_width() / 2, bar.get_height()), ha="center",
                        va="bottom", fontsize=8)  # fmt: skip
        ax.set_xticks(range(len(names)), [methods[n].label for n in names], fontsize=8)
        arrow = {"lower": " ↓", "higher": " ↑", None: ""}[info.better]
        ax.set_title(f"{info.label}{arrow}", fontsize=9)
        if info.unit:
            ax.set_ylabel(info.unit, fontsize=8)
        ax.tick_params(axis="y", labelsize=8)
        ax.margins(y=0.2)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return keys


def _write_png(path: Path, image: np.ndarray) -> None:
    if not cv2.imwrite(str(path), cv2.cvtColor(image, cv2.COLOR_RGB2BGR)):
        raise OSError(f"{path}: could not write PNG")


def write_stills(
    stage: Path, methods: Mapping[str, MethodResult], driver: DriverInfo, gt: GroundTruth | None, height: int
) -> list[tuple[int, str]]:
    """One PNG per still frame: driver | each method with its skeleton | ground truth with its skeleton.

    The frames shown are those every method has a still of.

    Returns:
        (frame index, file name) per still.
    """
    frames = sorted(set.intersection(*(set(m.stills) for m in methods.values()))) if methods else []
    track = driver.poses
    out = []
    for t in frames:
        if t >= track.num_frames:
            raise ValueError(f"still frame {t} is past the driver's {track.num_frames} frames")
        panels = [pose_panel(track.joints[t], track.layout, track.image_size, height)]
        labels = ["Driver"]
        for m in methods.values():
            panels.append(overlay(m.stills[t], m.still_poses.get(t), m.poses.layout))
            labels.append(m.label)
        if gt is not None and t in gt.stills:
            panels.append(overlay(gt.stills[t], gt.still_poses.get(t), gt.layout))
            labels.append("Ground truth")
        name = f"still_{t:05d}.png"
        _write_png(stage / name, side_by_side(panels, labels, height))
        out.append((t, name))
    return out


# --------------------------------------------------------------------------------------------------- page

_CSS = """
body{font:15px/1.45 system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;margin:0;background:#f4f5f7;color:#1d2330}
main{max-width:1180px;margin:0 auto;padding:20px 28px 40px}
h1{font-size:24px;margin:6px 0 2px}h2{font-size:18px;margin:28px 0 10px;border-bottom:1px solid #d8dbe2;padding-bottom:4px}
.sub{color:#5a6272;margin:0 0 14px}
section{background:#fff;border-radius:8px;padding:4px 18px 16px;margin-top:16px;box-shadow:0 1px 2px rgba(0,0,0,.06)}
dl{display:grid;grid-template-columns:max-content 1fr;gap:4px 16px;margin:8px 0}dt{color:#5a6272}dd{margin:0;word-break:break-all}
table{border-collapse:collapse;width:100%;font-variant-numeric:tabular-nums}
th,td{padding:5px 10px;border-bottom:1px solid #e6e8ed;text-align:right}th{background:#f0f2f5;font-weight:600}
td:first-child,th:first-child{text-align:left}td.unit{color:#7a8190;font-size:13px;text-align:left}
td.best{background:#dff3e2;font-weight:700;color:#12611f}td.base{color:#8a909c}
.swatch{display:inline-block;width:10px;height:10px;border-radius:2px;margin-right:6px;vertical-align:baseline}
video,img{display:block;width:100%;height:auto;border-radius:6px;background:#000}
img.plot{background:#fff}figure{margin:14px 0}figcaption{color:#5a6272;font-size:13px;margin-top:4px}
.note{color:#5a6272;font-size:13px}details{margin-top:12px}summary{cursor:pointer;color:#34405a}ul.defs{padding-left:18px;font-size:14px}ul.defs li{margin:3px 0}
"""


_BEST = ' class="best"'  # a table cell holding the better value


def _row(cells: Sequence[str]) -> str:
    return "<tr>" + "".join(cells) + "</tr>"


def _summary_table(methods: Mapping[str, MethodResult], driver: DriverInfo, colors: dict[str, str]) -> str:
    keys = [k for k in METRICS if any(k in m.scores.summary for m in methods.values())]
    base = driver.scores
    head = ["<th>Measure</th>", "<th></th>"]
    head += [
        f'<th><span class="swatch" style="background:{colors[n]}"></span>{html.escape(m.label)}</th>'
        for n, m in methods.items()
    ]
    if base is not None:
        head.append('<th title="the driver measured against itself">Driver (input)</th>')
    rows = [_row(head)]
    for key in keys:
        info = METRICS[key]
        best = best_methods(methods, key)
        arrow = {"lower": "lower is better", "higher": "higher is better", None: "context"}[info.better]
        cells = [
            f'<td title="{html.escape(info.meaning)}">{html.escape(info.label)}</td>',
            f'<td class="unit">{html.escape(" · ".join(filter(None, (info.unit, arrow))))}</td>',
        ]
        for name, m in methods.items():
            v = m.scores.summary.get(key, float("nan"))
            cells.append(f"<td{_BEST if name in best else ''}>{_fmt(v, info.scale)}</td>")
        if base is not None:
            cells.append(f'<td class="base">{_fmt(base.summary.get(key, float("nan")), info.scale)}</td>')
        rows.append(_row(cells))
    return "<table>" + "".join(rows) + "</table>"


def _limb_table(methods: Mapping[str, MethodResult]) -> str:
    """Per-limb length error of every method (best per limb highlighted), or "" when none has it."""
    key = "limb_error_pct_per_limb"
    per = {n: m.scores.details.get(key) for n, m in methods.items()}
    per = {n: v for n, v in per.items() if isinstance(v, Mapping)}
    if not per:
        return ""
    limbs = list(next(iter(per.values())))
    rows = [_row(["<th>Limb</th>", *(f"<th>{html.escape(methods[n].label)}</th>" for n in per)])]
    for limb in limbs:
        values = {n: float(v.get(limb, float("nan"))) for n, v in per.items()}
        finite = [v for v in values.values() if not math.isnan(v)]
        best = min(finite) if len(set(finite)) > 1 else None
        cells = [f"<td>{html.escape(limb)}</td>"]
        cells += [f"<td{_BEST if v == best else ''}>{_fmt(v)}</td>" for v in values.values()]
        rows.append(_row(cells))
    return (
        "<details><summary>Limb-length error per limb (% of height)</summary>"
        f"<table>{''.join(rows)}</table></details>"
    )


def render_page(
    methods: Mapping[str, MethodResult],
    driver: DriverInfo,
    gt: GroundTruth | None,
    video: str | None,
    stills: Sequence[tuple[int, str]],
    has_curves: bool,
    has_summary: bool,
) -> str:
    """The report page as one HTML string (inline CSS; media by relative file name)."""
    esc = html.escape
    track = driver.poses
    colors = _colors(methods)
    labels = [m.label for m in methods.values()]
    title = f"clone2d report: {Path(driver.source).name} on {Path(driver.reference).name}"
    stamp = _dt.datetime.now().strftime("%Y-%m-%d %H:%M")
    size = f"{track.image_size[0]}×{track.image_size[1]}"
    compared = [
        ("Driver poses", f"{esc(driver.source)} — {track.num_frames} frames at {track.fps:g} fps, {size}"),
        ("Reference model", esc(driver.reference)),
    ]
    for m in methods.values():
        compared.append((esc(m.label), esc(m.description) or "—"))
    if gt is not None:
        compared.append(("Ground-truth poses", esc(gt.poses_source or "not given")))
        compared.append(("Ground-truth frames", esc(gt.frames_source or "not given")))
    else:
        compared.append(("Ground truth", "not given: only measures that need no ground truth"))
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{esc(title)}</title><style>{_CSS}</style></head><body><main>",
        f"<h1>{esc(title)}</h1>",
        f'<p class="sub">{esc(" vs ".join(labels))} · generated {stamp} by clone2d</p>',
        "<section><h2>What was compared</h2><dl>",
        "".join(f"<dt>{k}</dt><dd>{v}</dd>" for k, v in compared),
        "</dl></section>",
        "<section><h2>Summary</h2>",
        _summary_table(methods, driver, colors),
        _limb_table(methods),
        (
            '<p class="note">The better value of each measure is highlighted. Lengths are in % of the '
            "reference's height (nose-to-ankle bone length). Hover a measure for its definition; all numbers "
            f'and per-frame curves are in <a href="{METRICS_FILE}">{METRICS_FILE}</a>.</p></section>'
        ),
    ]
    if video is not None:
        columns = ["Driver", *labels] + (["Ground truth"] if gt is not None and gt.frames_source else [])
        parts += [
            "<section><h2>Side by side</h2>",
            f'<video controls muted loop playsinline preload="metadata" src="{esc(video)}"></video>',
            f'<p class="note">{esc(" | ".join(columns))} · <a href="{esc(video)}">{esc(video)}</a></p>',
            "</section>",
        ]
    if has_curves or has_summary:
        parts.append("<section><h2>Plots</h2>")
        if has_summary:
            parts.append(
                f'<figure><img class="plot" src="{SUMMARY}" alt="summary bar charts">'
                "<figcaption>Summary per measure (arrows: which way is better).</figcaption></figure>"
            )
        if has_curves:
            parts.append(
                f'<figure><img class="plot" src="{CURVES}" alt="per-frame curves">'
                "<figcaption>Per-frame curves; gaps are frames without a value.</figcaption></figure>"
            )
        parts.append("</section>")
    if stills:
        parts.append("<section><h2>Still frames</h2>")
        for t, name in stills:
            parts.append(
                f'<figure><img src="{esc(name)}" alt="frame {t}"><figcaption>Frame {t} '
                f"({t / track.fps:.2f} s), skeletons drawn over the frames.</figcaption></figure>"
            )
        parts.append("</section>")
    defs = "".join(
        f"<li><b>{esc(m.label)}</b> ({esc(m.unit) or 'no unit'}): {esc(m.meaning)}</li>"
        for k, m in METRICS.items()
        if any(k in r.scores.summary for r in methods.values())
    )
    parts += [f'<section><h2>How the measures are defined</h2><ul class="defs">{defs}</ul></section>']
    parts.append("</main></body></html>\n")
    return "\n".join(parts)


def write_report_files(
    stage: Path,
    methods: Mapping[str, MethodResult],
    driver: DriverInfo,
    gt: GroundTruth | None = None,
    video: str | None = VIDEO,
    still_height: int = 320,
) -> Path:
    """Write metrics.json, the plots, the stills and report.html into ``stage``.

    Args:
        stage: the (temporary) report folder.
        methods: name -> result, in column order.
        driver: what drove the reference.
        gt: the ground truth, if any.
        video: file name of the side-by-side video already in ``stage``, or None for no video.
        still_height: rows of each still's image part.

    Returns:
        Path of the page.
    """
    if not methods:
        raise ValueError("write_report: no methods to report")
    if video is not None and not (stage / video).is_file():
        raise FileNotFoundError(f"{stage / video}: the side-by-side video is missing")
    with open(stage / METRICS_FILE, "w", encoding="utf-8") as f:
        json.dump(metrics_document(methods, driver, gt), f, indent=1, allow_nan=False)
    has_curves = bool(plot_curves(stage / CURVES, methods, driver.poses.fps))
    has_summary = bool(plot_summary(stage / SUMMARY, methods))
    stills = write_stills(stage, methods, driver, gt, still_height)
    page = render_page(methods, driver, gt, video, stills, has_curves, has_summary)
    (stage / PAGE).write_text(page, encoding="utf-8")
    return stage / PAGE


def write_report(
    out_dir: str | os.PathLike,
    methods: Mapping[str, MethodResult],
    driver: DriverInfo,
    gt: GroundTruth | None = None,
    video: str | os.PathLike | None = None,
    overwrite: bool = False,
) -> Path:
    """Write a whole report folder atomically (see the module docstring).

    Args:
        out_dir: the report folder; an existing one must be a report and needs ``overwrite``.
        methods: name -> result, in column order.
        driver: what drove the reference.
        gt: the ground truth, if any.
        video: a finished side-by-side mp4, copied in as ``side_by_side.mp4``; None for a page without video.
        overwrite: replace an existing report folder.

    Returns:
        Path of report.html in its final place.
    """
    out_dir = Path(out_dir)
    if video is not None and not Path(video).is_file():
        raise InputError(f"{video}: no such video")
    with report_dir(out_dir, overwrite) as stage:
        if video is not None:
            shutil.copyfile(video, stage / VIDEO)
        write_report_files(stage, methods, driver, gt, VIDEO if video is not None else None)
    log.info("report written to %s", out_dir)
    return out_dir / PAGE


# --------------------------------------------------------------------------------------------- the run

# The methods a report compares, in column order: drive method -> (column label, one-line description).
REPORT_METHODS: dict[str, tuple[str, str]] = {
    "global-scale": (
        "Global scaling",
        (
            "Everybody Dance Now's global normalisation: the driver scaled and moved per frame from its feet "
            "range onto the reference's, so it keeps the driver's own proportions."
        ),
    ),
    "retarget": (
        "Retargeted",
        (
            "the retargeting network (Aberman et al. 2019): the driver's motion code decoded with the "
            "reference's skeleton and view codes."
        ),
    ),
}


@dataclass(frozen=True)
class ReportRun:
    """What `clone report` wrote.

    Attributes:
        page: the report page.
        frames: frames compared.
        summary: method -> its summary numbers.
        seconds: wall time of the run.
    """

    page: Path
    frames: int
    summary: dict[str, dict[str, float]]
    seconds: float


def read_gt_poses(path: str | os.PathLike, num_frames: int, image_size: tuple[int, int]) -> PoseTrack:
    """Ground-truth poses as body15, checked against the driver's length and the reference's frame size.

    Args:
        path: any pose file or folder ``pose_io`` reads.
        num_frames: the driver's frame count.
        image_size: (width, height) of the reference's frames; used when the file stores no size.

    Raises:
        InputError: a different number of frames, or a stored size that differs from ``image_size``.
    """
    from pose_io.readers import read_track_summary

    summary = read_track_summary(path, fallback_size=image_size)
    track = summary.track
    if len(track) != num_frames:
        raise InputError(f"{path}: ground-truth poses have {len(track)} frames, the driver has {num_frames}")
    if track.image_size != tuple(image_size):
        if summary.size_source in ("file", "given"):
            raise InputError(
                f"{path}: ground-truth poses are for {track.image_size[0]}x{track.image_size[1]} frames, "
                f"the reference model's frames are {image_size[0]}x{image_size[1]}"
            )
        track = track.replace(image_size=image_size)  # the file stores no size: the reference's is meant
    return track.to_layout("body15")


def open_gt_frames(path: str | os.PathLike, num_frames: int, image_size: tuple[int, int]) -> Frames:
    """Ground-truth frames (video or image folder), checked against the driver's length and the reference's size.

    Returns:
        A re-iterable ``pose_io.video.Frames``.

    Raises:
        InputError: unreadable, a different number of frames, or a frame size other than ``image_size``.
    """
    from pose_io.video import read_frames

    frames = read_frames(path)
    if tuple(frames.size) != tuple(image_size):
        raise InputError(
            f"{path}: ground-truth frames are {frames.size[0]}x{frames.size[1]}, the reference model's frames "
            f"are {image_size[0]}x{image_size[1]}"
        )
    if frames.num_frames != num_frames:
        raise InputError(
            f"{path}: {frames.num_frames} ground-truth frames, the driver has {num_frames} frames"
        )
    return frames


def make_report(
    driver_path: str | os.PathLike,
    out_dir: str | os.PathLike,
    *,
    model_path: str | os.PathLike,
    gt_poses: str | os.PathLike | None = None,
    gt_frames: str | os.PathLike | None = None,
    overwrite: bool = False,
    device: str = "cpu",
    weights: str | os.PathLike | None = None,
    max_gap: int = 5,
    progress: Callable[[int, int], None] | None = None,
) -> ReportRun:
    """Drive the reference model with both methods, measure them and write the report folder.

    Every frame is generated once and used three ways (video, frame scores, stills), so memory does not
    grow with the driver's length.

    Args:
        driver_path: the driver's poses (any format ``pose_io`` reads).
        out_dir: the report folder (see ``write_report`` for the overwrite rules).
        model_path: the reference model from ``clone train-ref``.
        gt_poses: poses of the reference really performing the driver's motion, frame for frame.
        gt_frames: frames (video or image folder) of the same, the reference's frame size.
        overwrite: replace an existing report folder.
        device: where the networks run.
        weights: retargeting weights (default: see ``clone.drive.retargeting_weights``).
        max_gap: fill driver gaps of at most this many frames.
        progress: called with (frames done, total) after every frame.

    Returns:
        Where the page is and the summary numbers.
    """
    from clone.canvas import cut_frame, image_to_canvas
    from clone.drive import generate_frames, move_onto_reference, read_driver
    from clone.reference_model import load_reference_model
    from pose_io.video import VideoWriter

    t0 = time.perf_counter()
    out_dir = Path(out_dir)
    check_report_dir(out_dir, overwrite)  # before any slow work
    model = load_reference_model(model_path)
    canvas = model.canvas
    driver = read_driver(driver_path, max_gap)
    total = driver.num_frames
    truth = None if gt_poses is None else read_gt_poses(gt_poses, total, canvas.image_size)
    truth_frames = None if gt_frames is None else open_gt_frames(gt_frames, total, canvas.image_size)

    reference = model.reference_track
    ref_lengths = reference_limb_lengths(reference.joints, reference.layout)
    height = skeleton_height(reference.joints, reference.layout)
    driven = {m: move_onto_reference(driver, model, m, weights, device) for m in REPORT_METHODS}
    truth_canvas = None if truth is None else image_to_canvas(truth.joints, canvas)  # [T, J, 2] canvas px
    scorers = {m: FrameScorer(truth_canvas) for m in driven} if truth_frames is not None else {}
    at = set(still_indices(total))
    stills: dict[str, dict[int, np.ndarray]] = {m: {} for m in driven}
    gt_stills: dict[int, np.ndarray] = {}
    panel_height = min(max(canvas.size, 256), 512)  # small canvases are scaled up so captions stay legible
    labels = ["Driver", *(REPORT_METHODS[m][0] for m in driven)] + (["Ground truth"] if truth_frames else [])

    with report_dir(out_dir, overwrite) as stage:
        streams = [generate_frames(model, track, device) for track in driven.values()]
        gt_stream = iter(truth_frames) if truth_frames is not None else None
        with VideoWriter(stage / VIDEO, fps=driver.fps) as video:
            for t, outputs in enumerate(zip(*streams)):
                frames = [frame for _pose_map, frame in outputs]  # [S, S, 3] uint8 each
                panels = [
                    pose_panel(driver.joints[t], driver.layout, driver.image_size, panel_height),
                    *frames,
                ]
                if gt_stream is not None:
                    full = next(gt_stream, None)
                    if full is None:
                        raise InputError(f"{gt_frames}: ran out of frames at frame {t} of {total}")
                    true_frame = cut_frame(full, canvas)  # the generator's view of the true frame
                    panels.append(true_frame)
                    for m, frame in zip(driven, frames):
                        scorers[m].add(frame, true_frame)
                    if t in at:
                        gt_stills[t] = true_frame
                if t in at:
                    for m, frame in zip(driven, frames):
                        stills[m][t] = frame
                video.write(side_by_side(panels, labels, panel_height))
                if progress is not None:
                    progress(t + 1, total)

        methods: dict[str, MethodResult] = {}
        for m, track in driven.items():
            scores = evaluate_track(track, ref_lengths, height, truth)
            if m in scorers:
                scores = scores.merged(scorers[m].scores())
            poses_canvas = image_to_canvas(track.joints[sorted(at)], canvas)  # [S, J, 2]
            label, description = REPORT_METHODS[m]
            methods[m] = MethodResult(
                label, track, scores, stills[m], dict(zip(sorted(at), poses_canvas)), description
            )
        gt_info = None
        if truth is not None or truth_frames is not None:
            gt_poses_canvas = {} if truth_canvas is None else {t: truth_canvas[t] for t in gt_stills}
            gt_info = GroundTruth(
                None if gt_poses is None else str(gt_poses),
                None if gt_frames is None else str(gt_frames),
                gt_stills,
                gt_poses_canvas,
            )
        info = DriverInfo(driver, str(driver_path), str(model_path), _driver_baseline(driver))
        write_report_files(stage, methods, info, gt_info, VIDEO)
    summary = {m: dict(r.scores.summary) for m, r in methods.items()}
    return ReportRun(out_dir / PAGE, total, summary, time.perf_counter() - t0)


def _driver_baseline(driver: PoseTrack) -> Scores | None:
    """The driver measured against its own proportions and height (None when it has no full skeleton)."""
    try:
        return evaluate_track(driver, reference_limb_lengths(driver.joints, driver.layout),
                              skeleton_height(driver.joints, driver.layout))  # fmt: skip
    except InputError as exc:
        log.warning("no driver baseline: %s", exc)
        return None
