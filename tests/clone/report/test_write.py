"""A whole report written from measured results: its files, its numbers and its page."""

from __future__ import annotations

import json
import re

import cv2
import pytest

from clone.report.panels import caption_height, still_indices
from clone.report.write import write_report, write_report_files
from pose_io import BODY15, InputError, measures
from tests.clone.report.helpers import make_methods, walk, write_video


def test_report_files_numbers_and_page(tmp_path):
    methods, info, gt = make_methods()
    video = write_video(tmp_path / "v.mp4")
    out = tmp_path / "rep"
    page_path = write_report(out, methods, info, gt, video=video)
    names = {p.name for p in out.iterdir()}
    stills = sorted(n for n in names if n.startswith("still_"))
    assert names == {".clone2d-report", "report.html", "metrics.json", "side_by_side.mp4", "curves.png",
                     "summary.png", *stills}  # fmt: skip
    assert stills == [f"still_{t:05d}.png" for t in still_indices(12, 3)]

    # metrics.json: strict JSON (no NaN/Infinity literals), per-frame arrays of driver length
    def no_constants(name: str) -> None:
        raise AssertionError(f"non-standard JSON constant {name}")

    doc = json.loads((out / "metrics.json").read_text(), parse_constant=no_constants)
    assert doc["format"] == "clone2d-report-metrics" and doc["driver"]["frames"] == 12
    rt = doc["methods"]["retarget"]
    assert rt["summary"]["pose_mse"] == 0.0 and rt["summary"]["pck_0.05"] == 1.0
    assert rt["summary"]["psnr"] == "inf" and rt["per_frame"]["psnr"] == ["inf"] * 12  # identical frames
    assert rt["per_frame"]["foot_slide_pct"][0] is None  # no slide before the first frame
    gs = doc["methods"]["global-scale"]
    assert gs["summary"]["root_rmse_pct"] == pytest.approx(3.0 / measures.skeleton_height(walk(12).joints) * 100)
    assert gs["summary"]["pose_rmse_pct"] == pytest.approx(0.0, abs=1e-9)  # a shift is placement, not pose
    assert all(len(v) == 12 for v in gs["per_frame"].values())
    assert doc["metrics"]["pose_mse"]["display_scale"] == 1000.0

    page = page_path.read_text()
    # every link is relative and points at a file of the folder
    links = re.findall(r'(?:src|href)="([^"]+)"', page)
    assert links and all("://" not in ln and not ln.startswith("/") for ln in links)
    assert all((out / ln).is_file() for ln in links)
    assert set(stills) | {"curves.png", "summary.png", "side_by_side.mp4", "metrics.json"} <= set(links)
    assert "<video controls muted loop playsinline" in page and "<script" not in page
    # retargeted poses equal the truth: it holds the better placement, highlighted; PSNR inf shown as ∞
    row = re.search(r"Placement \(root error\)</td>(.*?)</tr>", page).group(1)
    cells = re.findall(r"<td([^>]*)>([^<]*)</td>", row)[1:]
    assert cells[0] == ("", f"{gs['summary']['root_rmse_pct']:.3g}") and cells[1] == (' class="best"', "0")
    assert re.search(r"PSNR \(frame\)</td>.*?<td class=\"best\">∞</td>", page)
    # per-limb breakdown: the shifted copy has the same limb lengths, so no limb has a better method
    limbs = re.search(r"Limb-length error per limb.*?</table>", page).group(0)
    assert limbs.count("<tr>") == 1 + len(BODY15.limbs) and 'class="best"' not in limbs

    for name in stills + ["curves.png", "summary.png"]:
        img = cv2.imread(str(out / name))
        assert img is not None and img.shape[0] > 50
    still = cv2.imread(str(out / stills[0]))
    # driver | 2 methods | ground truth, each scaled to 320 rows under a caption strip
    assert still.shape[0] == 320 + caption_height(320) and still.shape[1] >= 4 * 320 - 1


def test_write_report_files_checks_its_inputs(tmp_path):
    methods, info, gt = make_methods(frames=6, with_frames=False)
    with pytest.raises(ValueError, match="no methods"):
        write_report_files(tmp_path, {}, info, gt)
    with pytest.raises(FileNotFoundError, match="side-by-side video is missing"):
        write_report_files(tmp_path, methods, info, gt)  # the default expects side_by_side.mp4 in place
    assert list(tmp_path.iterdir()) == []  # both refused before writing anything
    with pytest.raises(InputError, match="no such video"):
        write_report(tmp_path / "rep", methods, info, gt, video=tmp_path / "missing.mp4")
    assert list(tmp_path.iterdir()) == []

    page = write_report_files(tmp_path, methods, info, None, video=None, still_height=64)
    assert page == tmp_path / "report.html" and "<video" not in page.read_text()
    assert cv2.imread(str(tmp_path / f"still_{still_indices(6, 3)[0]:05d}.png")).shape[
        0
    ] == 64 + caption_height(64)
