"""The report's two plots: per-frame curves of every measure and one bar chart per summary measure.

Drawn with matplotlib's object API (``Figure`` + ``savefig``): no pyplot, and the user's backend stays as it
was, so the report can be made from a notebook or a GUI without changing how that session draws.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from clone.metrics import METRICS
from clone.report.results import MethodResult, format_value, method_colors, summary_keys

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

_ARROWS = {"lower": " ↓", "higher": " ↑", None: ""}
_DPI = 100


def _figure(
    panels: int, cols: int, row_inches: float, extra_inches: float, sharex: bool = False
) -> tuple[Figure, np.ndarray]:
    """A figure of ``panels`` axes on a grid ``cols`` wide, 11 inches across; unused axes are hidden.

    Args:
        panels: axes in use.
        cols: axes per row.
        row_inches: height of one row.
        extra_inches: height added for titles and legend.
        sharex: share the x axis between all axes.

    Returns:
        (figure, [rows, cols] array of axes).
    """
    from matplotlib.figure import Figure  # matplotlib is slow to import and only reports need it

    rows = math.ceil(panels / cols)
    fig = Figure(figsize=(11, row_inches * rows + extra_inches))
    axes = fig.subplots(rows, cols, sharex=sharex, squeeze=False)
    for ax in axes.flat[panels:]:
        ax.axis("off")
    return fig, axes


def _curve_axes(
    ax: Axes, key: str, methods: Mapping[str, MethodResult], colors: dict[str, str], fps: float
) -> None:
    """Draw the per-frame values of measure ``key`` of every method that has them, one line each."""
    info = METRICS[key]
    for name, m in methods.items():
        if key not in m.scores.per_frame:
            continue
        y = np.asarray(m.scores.per_frame[key], dtype=np.float64) * info.scale  # [T]
        y = np.where(np.isinf(y), np.nan, y)  # identical frames have no finite PSNR to draw
        t = np.arange(len(y)) / fps
        ax.plot(t, y, color=colors[name], lw=1.1, label=m.label, marker="." if len(y) < 60 else None)
    ax.set_title(f"{info.label} ({info.unit})" if info.unit else info.label, fontsize=9)
    ax.tick_params(labelsize=8)
    ax.grid(alpha=0.3)


def plot_curves(path: Path, methods: Mapping[str, MethodResult], fps: float) -> list[str]:
    """Per-frame curves of every measure (one panel each, two columns, one line per method) as a PNG.

    Args:
        path: the PNG to write.
        methods: name -> result, in column order.
        fps: frames per second of the per-frame values (the x axis is in seconds).

    Returns:
        The measures plotted, in order (none: no file written).
    """
    keys = [k for k in METRICS if any(k in m.scores.per_frame for m in methods.values())]
    if not keys:
        return []
    colors = method_colors(methods)
    fig, axes = _figure(len(keys), 2 if len(keys) > 1 else 1, 2.0, 0.5, sharex=True)
    for ax, key in zip(axes.flat, keys):
        _curve_axes(ax, key, methods, colors, fps)
    for ax in axes[-1]:
        ax.set_xlabel("time (s)", fontsize=8)
        ax.xaxis.set_tick_params(labelbottom=True)
    handles, labels = axes.flat[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="upper center", ncol=len(labels), fontsize=9, frameon=False)
    fig.tight_layout(rect=(0, 0, 1, 1 - 0.35 / fig.get_figheight()))
    fig.savefig(path, dpi=_DPI)
    return keys


def _bar_axes(ax: Axes, key: str, methods: Mapping[str, MethodResult], colors: dict[str, str]) -> None:
    """Draw the summary value of measure ``key`` of every method that has it, one labelled bar each.

    An infinite value is drawn a little above the tallest finite bar, a missing one as an empty bar; the
    label above the bar says which.
    """
    info = METRICS[key]
    names = [n for n, m in methods.items() if key in m.scores.summary]
    values = [methods[n].scores.summary[key] * info.scale for n in names]
    finite = [v for v in values if math.isfinite(v)]
    top = max(finite) if finite else 1.0
    drawn = [top * 1.1 if math.isinf(v) else (0.0 if math.isnan(v) else v) for v in values]
    bars = ax.bar(range(len(names)), drawn, color=[colors[n] for n in names])
    for bar, v in zip(bars, values):
        ax.annotate(format_value(v), (bar.get_x() + bar.get_width() / 2, bar.get_height()), ha="center",
                    va="bottom", fontsize=8)  # fmt: skip
    ax.set_xticks(range(len(names)), [methods[n].label for n in names], fontsize=8)
    ax.set_title(f"{info.label}{_ARROWS[info.better]}", fontsize=9)
    if info.unit:
        ax.set_ylabel(info.unit, fontsize=8)
    ax.tick_params(axis="y", labelsize=8)
    ax.margins(y=0.2)


def plot_summary(path: Path, methods: Mapping[str, MethodResult]) -> list[str]:
    """One small bar chart per summary measure (one bar per method, up to four charts a row) as a PNG.

    Args:
        path: the PNG to write.
        methods: name -> result, in column order.

    Returns:
        The measures plotted, in order (none: no file written).
    """
    keys = summary_keys(methods)
    if not keys:
        return []
    colors = method_colors(methods)
    fig, axes = _figure(len(keys), min(4, len(keys)), 2.3, 0.3)
    for ax, key in zip(axes.flat, keys):
        _bar_axes(ax, key, methods, colors)
    fig.tight_layout()
    fig.savefig(path, dpi=_DPI)
    return keys
