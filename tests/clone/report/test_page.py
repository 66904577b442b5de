"""report.html: what the page says, and the page in headless Chromium."""

from __future__ import annotations

import json
import re
import shutil
import subprocess

import cv2
import pytest

from clone.metrics import Scores
from clone.report.page import render_page
from clone.report.panels import caption_height, still_indices
from clone.report.results import DriverInfo, MethodResult
from clone.report.write import write_report
from tests.clone.report.helpers import SIZE, make_methods, write_video


def test_page_without_video_plots_or_truth():
    methods, info, _ = make_methods(frames=6, with_frames=False)
    methods["retarget"] = MethodResult("<b>Ret</b>", methods["retarget"].poses, methods["retarget"].scores,
                                       description="a & b")  # fmt: skip
    info = DriverInfo(info.poses, "drv/poses.npz", "ref_model.pt", Scores(summary={"pose_mse": 0.5}))
    page = render_page(methods, info, None, None, [], False, False)
    assert page.startswith("<!DOCTYPE html>") and page.endswith("</main></body></html>\n")
    assert "<video" not in page and "<img" not in page and "<script" not in page
    assert "<b>Ret</b>" not in page and "&lt;b&gt;Ret&lt;/b&gt;" in page and "a &amp; b" in page
    assert "Ground truth</dt><dd>not given" in page
    assert "<title>clone2d report: poses.npz on ref_model.pt</title>" in page
    assert "Driver (input)" in page and '<td class="base">500.0</td>' in page  # pose MSE shown ×1000

    assert "never showed" not in page  # no coverage measured: no note

    covered = methods["retarget"].scores.merged(Scores(
        summary={"uncovered_share": 0.25}, details={"uncovered_parts": {"arms above the head": 0.2, "legs": 0.001}}))
    methods["retarget"] = MethodResult("<b>Ret</b>", methods["retarget"].poses, covered)
    page = render_page(methods, info, None, None, [], False, False)
    assert "&lt;b&gt;Ret&lt;/b&gt;: 25% of the frames (arms above the head 20%)" in page and "legs 0%" not in page

    stills = [(3, "still_00003.png")]
    page = render_page(methods, info, None, "v.mp4", stills, True, False)
    assert 'src="v.mp4"' in page and 'src="curves.png"' in page and 'src="summary.png"' not in page
    assert "Frame 3 (0.10 s)" in page and "Driver | Global scaling | &lt;b&gt;Ret&lt;/b&gt;" in page


_CHECK = """<script>
window.addEventListener('load', () => {
  const imgs = [...document.images];
  const vids = [...document.querySelectorAll('video')];
  let reported = false;
  const done = () => {
    if (reported) return;
    reported = true;
    document.body.dataset.check = JSON.stringify({
      images: imgs.length,
      bad: imgs.filter(i => !(i.complete && i.naturalWidth > 0)).map(i => i.getAttribute('src')),
      videos: vids.map(v => ({src: v.getAttribute('src'), w: v.videoWidth, h: v.videoHeight,
                               error: v.error ? v.error.code : null}))});
  };
  const settled = v => v.readyState >= 1 || v.error !== null;
  const check = () => { if (vids.every(settled)) done(); };
  vids.forEach(v => ['loadedmetadata', 'error'].forEach(e => v.addEventListener(e, check)));
  check();
  setTimeout(done, 5000);  // report whatever state the videos reached
});
</script>"""


def _chromium() -> str | None:
    return shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which("google-chrome")


@pytest.mark.browser
def test_page_loads_in_chromium(tmp_path):
    """Headless Chromium opens the page: every image decodes, the video's metadata (H.264) loads."""
    browser = _chromium()
    if browser is None:
        pytest.skip("headless Chromium is not installed")
    methods, info, gt = make_methods()
    out = tmp_path / "rep"
    write_report(out, methods, info, gt, video=write_video(tmp_path / "v.mp4"))
    page = (out / "report.html").read_text()
    # a copy of the page, next to it, with a script that records what loaded into the DOM
    (out / "check.html").write_text(page.replace("</body>", _CHECK + "</body>"))
    profile = tmp_path / "profile"
    args = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
            "--disable-component-update", "--disable-sync", "--no-first-run", f"--user-data-dir={profile}",
            "--autoplay-policy=no-user-gesture-required", "--virtual-time-budget=10000", "--window-size=1366,900"]  # fmt: skip
    dom = subprocess.run([*args, "--dump-dom", (out / "check.html").as_uri()], capture_output=True, text=True, check=False,
                         timeout=120).stdout  # fmt: skip
    found = re.search(r'data-check="([^"]*)"', dom)
    assert found, f"the check script did not finish: {dom[-500:]}"
    check = json.loads(found.group(1).replace("&quot;", '"'))
    assert check["images"] == 2 + len(still_indices(12, 3)) and check["bad"] == []
    assert check["videos"] == [{"src": "side_by_side.mp4", "w": 2 * SIZE, "h": SIZE + caption_height(SIZE),
                                  "error": None}]  # fmt: skip
    shot = tmp_path / "shot.png"
    subprocess.run([*args, f"--screenshot={shot}", (out / "report.html").as_uri()], capture_output=True, check=False,
                   timeout=120)  # fmt: skip
    image = cv2.imread(str(shot))
    assert image is not None and image.shape[:2] == (900, 1366) and image.std() > 10  # something was drawn
