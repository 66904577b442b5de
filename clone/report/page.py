"""report.html: one self-contained page (inline CSS, no scripts, no network), media linked by file name."""

from __future__ import annotations

import datetime as _dt
import math
from collections.abc import Mapping, Sequence
from html import escape
from pathlib import Path

from clone.drive.coverage import describe_parts
from clone.metrics import METRICS
from clone.report.results import (
    CURVES,
    METRICS_FILE,
    SUMMARY,
    DriverInfo,
    GroundTruth,
    MethodResult,
    best_methods,
    format_value,
    method_colors,
    summary_keys,
)

CSS = """
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
_DIRECTION = {"lower": "lower is better", "higher": "higher is better", None: "context"}


def _row(cells: Sequence[str]) -> str:
    return "<tr>" + "".join(cells) + "</tr>"


def _summary_head(methods: Mapping[str, MethodResult], colors: dict[str, str], baseline: bool) -> str:
    """Header row of the summary table: measure, unit, one swatch + label per method, the driver."""
    head = ["<th>Measure</th>", "<th></th>"]
    head += [
        f'<th><span class="swatch" style="background:{colors[n]}"></span>{escape(m.label)}</th>'
        for n, m in methods.items()
    ]
    if baseline:
        head.append('<th title="the driver measured against itself">Driver (input)</th>')
    return _row(head)


def _summary_row(key: str, methods: Mapping[str, MethodResult], driver: DriverInfo) -> str:
    """One measure: its name and unit, each method's value (the better highlighted), the driver's value."""
    info = METRICS[key]
    best = best_methods(methods, key)
    cells = [
        f'<td title="{escape(info.meaning)}">{escape(info.label)}</td>',
        f'<td class="unit">{escape(" · ".join(filter(None, (info.unit, _DIRECTION[info.better]))))}</td>',
    ]
    for name, m in methods.items():
        v = m.scores.summary.get(key, float("nan"))
        cells.append(f"<td{_BEST if name in best else ''}>{format_value(v, info.scale)}</td>")
    if driver.scores is not None:
        v = driver.scores.summary.get(key, float("nan"))
        cells.append(f'<td class="base">{format_value(v, info.scale)}</td>')
    return _row(cells)


def _summary_table(methods: Mapping[str, MethodResult], driver: DriverInfo, colors: dict[str, str]) -> str:
    rows = [_summary_head(methods, colors, driver.scores is not None)]
    rows += [_summary_row(key, methods, driver) for key in summary_keys(methods)]
    return "<table>" + "".join(rows) + "</table>"


def _limb_table(methods: Mapping[str, MethodResult]) -> str:
    """Per-limb length error of every method (best per limb highlighted), or "" when none has it."""
    key = "limb_error_pct_per_limb"
    per = {n: m.scores.details.get(key) for n, m in methods.items()}
    per = {n: v for n, v in per.items() if isinstance(v, Mapping)}
    if not per:
        return ""
    limbs = list(next(iter(per.values())))
    rows = [_row(["<th>Limb</th>", *(f"<th>{escape(methods[n].label)}</th>" for n in per)])]
    for limb in limbs:
        values = {n: float(v.get(limb, float("nan"))) for n, v in per.items()}
        finite = [v for v in values.values() if not math.isnan(v)]
        best = min(finite) if len(set(finite)) > 1 else None
        cells = [f"<td>{escape(limb)}</td>"]
        cells += [f"<td{_BEST if v == best else ''}>{format_value(v)}</td>" for v in values.values()]
        rows.append(_row(cells))
    return (
        "<details><summary>Limb-length error per limb (% of height)</summary>"
        f"<table>{''.join(rows)}</table></details>"
    )


def _compared_section(methods: Mapping[str, MethodResult], driver: DriverInfo, gt: GroundTruth | None) -> str:
    """What was compared: the driver, the reference model, each method and the ground truth."""
    track = driver.poses
    size = f"{track.image_size[0]}×{track.image_size[1]}"
    compared = [
        ("Driver poses", f"{escape(driver.source)} — {track.num_frames} frames at {track.fps:g} fps, {size}"),
        ("Reference model", escape(driver.reference)),
    ]
    compared += [(escape(m.label), escape(m.description) or "—") for m in methods.values()]
    if gt is not None:
        compared.append(("Ground-truth poses", escape(gt.poses_source or "not given")))
        compared.append(("Ground-truth frames", escape(gt.frames_source or "not given")))
    else:
        compared.append(("Ground truth", "not given: only measures that need no ground truth"))
    items = "".join(f"<dt>{k}</dt><dd>{v}</dd>" for k, v in compared)
    return f"<section><h2>What was compared</h2><dl>\n{items}\n</dl></section>"


def _coverage_note(methods: Mapping[str, MethodResult]) -> str:
    """One paragraph naming, per method, the share of frames outside the reference's poses and what is new there
    (the line `clone drive` prints, :meth:`clone.drive.coverage.Coverage.line`); empty when every frame is covered."""
    items = []
    for m in methods.values():
        share = m.scores.summary.get("uncovered_share", 0.0)
        if not share or not share > 0:
            continue
        named = describe_parts(dict(m.scores.details.get("uncovered_parts", {})))
        items.append(f"{escape(m.label)}: {100 * share:.0f}% of the frames" + (f" ({escape(named)})" if named else ""))
    if not items:
        return ""
    return ('<p class="note"><b>Poses the reference never showed.</b> ' + "; ".join(items)
            + ". Expect holes and smears there: the generator learnt this person only in the poses of the "
            "reference video (the README's \u201cFilming a good reference\u201d says what to film).</p>")


def _summary_section(methods: Mapping[str, MethodResult], driver: DriverInfo) -> str:
    return "\n".join([
        "<section><h2>Summary</h2>",
        _summary_table(methods, driver, method_colors(methods)),
        _coverage_note(methods),
        _limb_table(methods),
        (
            '<p class="note">The better value of each measure is highlighted. Lengths are in % of the '
            "reference's height (nose-to-ankle bone length). Hover a measure for its definition; all numbers "
            f'and per-frame curves are in <a href="{METRICS_FILE}">{METRICS_FILE}</a>.</p></section>'
        ),
    ])  # fmt: skip


def _video_section(video: str, columns: Sequence[str]) -> str:
    return "\n".join([
        "<section><h2>Side by side</h2>",
        f'<video controls muted loop playsinline preload="metadata" src="{escape(video)}"></video>',
        f'<p class="note">{escape(" | ".join(columns))} · <a href="{escape(video)}">{escape(video)}</a></p>',
        "</section>",
    ])  # fmt: skip


def _plots_section(has_curves: bool, has_summary: bool) -> str:
    parts = ["<section><h2>Plots</h2>"]
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
    return "\n".join(parts)


def _stills_section(stills: Sequence[tuple[int, str]], fps: float) -> str:
    figures = [
        f'<figure><img src="{escape(name)}" alt="frame {t}"><figcaption>Frame {t} '
        f"({t / fps:.2f} s), skeletons drawn over the frames.</figcaption></figure>"
        for t, name in stills
    ]
    return "\n".join(["<section><h2>Still frames</h2>", *figures, "</section>"])


def _definitions_section(methods: Mapping[str, MethodResult]) -> str:
    defs = "".join(
        f"<li><b>{escape(m.label)}</b> ({escape(m.unit) or 'no unit'}): {escape(m.meaning)}</li>"
        for k, m in METRICS.items()
        if any(k in r.scores.summary for r in methods.values())
    )
    return f'<section><h2>How the measures are defined</h2><ul class="defs">{defs}</ul></section>'


def render_page(
    methods: Mapping[str, MethodResult],
    driver: DriverInfo,
    gt: GroundTruth | None,
    video: str | None,
    stills: Sequence[tuple[int, str]],
    has_curves: bool,
    has_summary: bool,
) -> str:
    """The report page as one HTML string (inline CSS; media by relative file name).

    Args:
        methods: name -> result, in column order.
        driver: what drove the reference.
        gt: the ground truth, if any.
        video: file name of the side-by-side video, or None for a page without video.
        stills: (frame index, file name) per still image.
        has_curves: whether the per-frame curves plot was written.
        has_summary: whether the summary bar charts were written.
    """
    labels = [m.label for m in methods.values()]
    title = escape(f"clone2d report: {Path(driver.source).name} on {Path(driver.reference).name}")
    stamp = _dt.datetime.now().strftime("%Y-%m-%d %H:%M")
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{title}</title><style>{CSS}</style></head><body><main>",
        f"<h1>{title}</h1>",
        f'<p class="sub">{escape(" vs ".join(labels))} · generated {stamp} by clone2d</p>',
        _compared_section(methods, driver, gt),
        _summary_section(methods, driver),
    ]
    if video is not None:
        truth_column = ["Ground truth"] if gt is not None and gt.frames_source else []
        parts.append(_video_section(video, ["Driver", *labels, *truth_column]))
    if has_curves or has_summary:
        parts.append(_plots_section(has_curves, has_summary))
    if stills:
        parts.append(_stills_section(stills, driver.poses.fps))
    parts += [_definitions_section(methods), "</main></body></html>\n"]
    return "\n".join(parts)
