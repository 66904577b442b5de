"""The overview over several report folders: read back from the folders, one table across pairs, links inside."""

from __future__ import annotations

import json
import math
import re

import pytest

from clone.report.overview import OVERVIEW_KEYS, read_section, render_overview, write_overview
from clone.report.write import write_report
from pose_io import InputError
from tests.clone.report.helpers import make_methods, write_video


def _pair_report(tmp_path, name):
    methods, info, gt = make_methods()
    folder = tmp_path / name / "report"
    write_report(folder, methods, info, gt, video=write_video(tmp_path / f"{name}.mp4"))
    return folder


def test_sections_read_back_and_the_page_links_into_the_folders(tmp_path):
    sections = [
        read_section(name, f"tests {name}", [("Driver", f"<{name}>")], _pair_report(tmp_path, name), tmp_path)
        for name in ("proportions", "view")
    ]
    first = sections[0]
    assert first.folder == "proportions/report" and first.stills and all(s.startswith("still_") for s in first.stills)
    assert list(first.labels) == ["global-scale", "retarget"]
    doc = json.loads((tmp_path / "proportions" / "report" / "metrics.json").read_text())
    assert first.summary["retarget"]["root_rmse_pct"] == doc["methods"]["retarget"]["summary"]["root_rmse_pct"]
    assert math.isinf(first.summary["retarget"]["psnr"])  # "inf" in metrics.json reads back as infinity

    page_path = write_overview(tmp_path / "report.html", "demo <1>", [("Reference", "tall & long")], sections,
                               ["a note"])  # fmt: skip
    page = page_path.read_text()
    assert page.startswith("<!DOCTYPE html>") and "<script" not in page
    assert "demo &lt;1&gt;" in page and "tall &amp; long" in page and "&lt;proportions&gt;" in page
    links = re.findall(r'(?:src|href)="([^"#]+)"', page)
    assert "proportions/report/side_by_side.mp4" in links and "view/report/report.html" in links
    assert all("://" not in ln and (tmp_path / ln).is_file() for ln in links)  # relative, and each one exists
    assert 'href="#pair-view"' in page and 'id="pair-view"' in page
    # The summary: the primary measure first, one row per method and the ratio row; the better value marked.
    table = re.search(r"<table>.*?</table>", page, re.DOTALL).group(0)
    order = [k for k in OVERVIEW_KEYS if k in first.summary["retarget"]]
    assert order[0] == "pose_rmse_pct" and table.index("Pose error (MidHip-aligned)") < table.index("Placement")
    placement = re.search(r"Placement \(root error\).*?</tr>(.*?)</tr>", table, re.DOTALL).group(1)
    assert placement.count('class="best"') == 2  # retargeted is where the truth is, in both pairs
    assert "Global scaling ÷ Retargeted" in table


def test_ratio_row_and_unreadable_folders(tmp_path):
    section = read_section("p", "t", [], _pair_report(tmp_path, "p"), tmp_path)
    summary = {m: dict(v) for m, v in section.summary.items()}
    summary["global-scale"]["pose_rmse_pct"], summary["retarget"]["pose_rmse_pct"] = 9.0, 4.0
    from dataclasses import replace

    from clone.report.overview import ratio

    section = replace(section, summary=summary)
    assert ratio(section) == pytest.approx(2.25)
    assert "<b>2.25×</b>" in render_overview("t", [], [section])
    summary["retarget"]["pose_rmse_pct"] = 0.0
    assert math.isnan(ratio(replace(section, summary=summary)))
    (tmp_path / "empty").mkdir()
    with pytest.raises(InputError, match="not a report's metrics"):
        read_section("e", "t", [], tmp_path / "empty", tmp_path)
