"""An overview page over several report folders: one summary table across pairs, then one section per pair.

`clone demo` drives one reference model with several drivers, each a `clone report` folder; this page sits
above them and links into them (relative links, so the whole demo folder can be moved or zipped). Everything
it shows is read back from the report folders (``metrics.json``, the stills, the video), so it never disagrees
with them.
"""

from __future__ import annotations

import datetime as _dt
import json
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from html import escape
from pathlib import Path

from clone.metrics import METRICS
from clone.report.page import CSS
from clone.report.results import METRICS_FILE, PAGE, VIDEO, best_of, format_value
from pose_io.atomic import atomic_file
from pose_io.errors import InputError

# The measures of the summary across pairs, in this order (the primary pose measure first); every other
# measure is on each pair's own page.
OVERVIEW_KEYS: tuple[str, ...] = (
    "pose_rmse_pct", "root_rmse_pct", "facing_share", "ssim_crop", "psnr_crop", "ssim", "psnr", "psnr_background",
    "limb_error_pct", "jitter_pct", "foot_slide_pct", "stage_share",
)  # fmt: skip
# The claim's ratio: how many times the first method's primary error is the second's.
RATIO_KEY = "pose_rmse_pct"
RATIO_METHODS = ("global-scale", "retarget")


@dataclass(frozen=True)
class PairSection:
    """One report folder as the overview shows it.

    Attributes:
        name: short name, also the section's anchor (``"view"``).
        title: what the pair tests, one line.
        details: (label, text) lines describing the pair (driver, ground truth, frames ...).
        folder: the report folder relative to the overview page, with ``/`` separators.
        labels: method -> column label, in column order.
        summary: method -> measure -> value (NaN where none).
        stills: file names of the still images inside ``folder``.
    """

    name: str
    title: str
    details: tuple[tuple[str, str], ...]
    folder: str
    labels: Mapping[str, str]
    summary: Mapping[str, Mapping[str, float]]
    stills: tuple[str, ...] = field(default_factory=tuple)


def _number(value: object) -> float:
    """A metrics.json value as a float: null -> NaN, "inf" / "-inf" -> infinities."""
    if value is None:
        return float("nan")
    return float(value)  # float("inf") reads the strings metrics.json writes for infinities


def read_section(
    name: str, title: str, details: Sequence[tuple[str, str]], report: str | os.PathLike, page_dir: str | os.PathLike
) -> PairSection:
    """A pair's section read from its report folder.

    Args:
        name: short name of the pair.
        title: what it tests.
        details: (label, text) lines describing it.
        report: the pair's report folder (``clone.report.make_report`` wrote it).
        page_dir: the folder the overview page will be in (links are made relative to it).

    Raises:
        InputError: the folder holds no readable metrics.json.
    """
    report = Path(report)
    try:
        doc = json.loads((report / METRICS_FILE).read_text(encoding="utf-8"))
        methods = doc["methods"]
        labels = {m: str(v["label"]) for m, v in methods.items()}
        summary = {m: {k: _number(x) for k, x in v["summary"].items()} for m, v in methods.items()}
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise InputError(f"{report / METRICS_FILE}: not a report's metrics ({exc})") from None
    stills = tuple(sorted(p.name for p in report.glob("still_*.png")))
    folder = Path(os.path.relpath(report, page_dir)).as_posix()
    return PairSection(name, title, tuple(details), folder, labels, summary, stills)


def ratio(section: PairSection, key: str = RATIO_KEY, methods: tuple[str, str] = RATIO_METHODS) -> float:
    """How many times ``methods[0]``'s value of ``key`` is ``methods[1]``'s (NaN when either is missing)."""
    a, b = (section.summary.get(m, {}).get(key, float("nan")) for m in methods)
    return a / b if b > 0 and math.isfinite(a) else float("nan")


def _summary_table(sections: Sequence[PairSection]) -> str:
    """Measures x methods down, pairs across; the better method of each pair and measure highlighted."""
    head = "<tr><th>Measure</th><th></th><th>Method</th>" + "".join(
        f'<th><a href="#pair-{escape(s.name)}">{escape(s.name)}</a></th>' for s in sections
    ) + "</tr>"
    methods = list(dict.fromkeys(m for s in sections for m in s.labels))
    labels = {m: next(s.labels[m] for s in sections if m in s.labels) for m in methods}
    rows = [head]
    for key in OVERVIEW_KEYS:
        if not any(key in s.summary.get(m, {}) for s in sections for m in methods):
            continue
        info = METRICS[key]
        best = [best_of({m: s.summary.get(m, {}).get(key) for m in methods}, key) for s in sections]
        for i, m in enumerate(methods):
            cells = []
            if i == 0:
                span = f' rowspan="{len(methods) + (key == RATIO_KEY)}"'
                cells.append(f'<td{span} title="{escape(info.meaning)}">{escape(info.label)}</td>')
                cells.append(f'<td{span} class="unit">{escape(info.unit)}</td>')
            cells.append(f"<td>{escape(labels[m])}</td>")
            for s, good in zip(sections, best):
                value = s.summary.get(m, {}).get(key)
                mark = ' class="best"' if m in good else ""
                cells.append(f"<td{mark}>{format_value(value, info.scale)}</td>")
            rows.append("<tr>" + "".join(cells) + "</tr>")
        if key == RATIO_KEY and all(m in methods for m in RATIO_METHODS):
            ratios = "".join(f"<td><b>{format_value(ratio(s))}×</b></td>" for s in sections)
            text = f"{labels[RATIO_METHODS[0]]} ÷ {labels[RATIO_METHODS[1]]}"
            rows.append(f"<tr><td>{escape(text)}</td>{ratios}</tr>")
    return "<table>" + "".join(rows) + "</table>"


def _pair_section(section: PairSection) -> str:
    """A pair's section: what it tests, its video and stills, and a link to its full report."""
    folder = escape(section.folder)
    items = "".join(f"<dt>{escape(k)}</dt><dd>{escape(v)}</dd>" for k, v in section.details)
    stills = "".join(
        f'<figure><img src="{folder}/{escape(n)}" alt="{escape(section.name)} {escape(n)}"><figcaption>'
        f"{escape(n)}: driver | methods | ground truth, skeletons drawn over the frames</figcaption></figure>"
        for n in section.stills
    )
    columns = " | ".join(escape(v) for v in section.labels.values())
    note = (
        f'<p class="note">Driver | {columns} | Ground truth · <a href="{folder}/{PAGE}">the full report of this '
        f'pair</a> (every measure, per-frame curves, <a href="{folder}/{METRICS_FILE}">{METRICS_FILE}</a>)</p>'
    )
    return "\n".join([
        f'<section id="pair-{escape(section.name)}"><h2>{escape(section.name)}: {escape(section.title)}</h2>',
        f"<dl>{items}</dl>",
        f'<video controls muted loop playsinline preload="metadata" src="{folder}/{VIDEO}"></video>',
        note,
        stills,
        "</section>",
    ])  # fmt: skip


def render_overview(
    title: str, intro: Sequence[tuple[str, str]], sections: Sequence[PairSection], notes: Sequence[str] = ()
) -> str:
    """The overview page as one HTML string (inline CSS, no scripts; media linked relatively).

    Args:
        title: page title.
        intro: (label, text) lines about the whole run (reference, setup, times).
        sections: one per pair, in order.
        notes: paragraphs under the summary table (how to read it).
    """
    stamp = _dt.datetime.now().strftime("%Y-%m-%d %H:%M")
    items = "".join(f"<dt>{escape(k)}</dt><dd>{escape(v)}</dd>" for k, v in intro)
    paragraphs = "".join(f'<p class="note">{escape(n)}</p>' for n in notes)
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{escape(title)}</title><style>{CSS}</style></head><body><main>",
        f"<h1>{escape(title)}</h1>",
        f'<p class="sub">{len(sections)} pairs · generated {stamp} by clone2d</p>',
        f"<section><h2>Setup</h2><dl>{items}</dl></section>",
        "<section><h2>Summary across pairs</h2>",
        _summary_table(sections),
        f"{paragraphs}</section>",
        *(_pair_section(s) for s in sections),
        "</main></body></html>\n",
    ]
    return "\n".join(parts)


def write_overview(
    path: str | os.PathLike,
    title: str,
    intro: Sequence[tuple[str, str]],
    sections: Sequence[PairSection],
    notes: Sequence[str] = (),
) -> Path:
    """Write :func:`render_overview` to ``path`` atomically (an existing page there is replaced)."""
    path = Path(path)
    with atomic_file(path) as tmp:
        tmp.write_text(render_overview(title, intro, sections, notes), encoding="utf-8")
    return path
