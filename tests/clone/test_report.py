"""The report writer (folder rules, files, page, numbers), `clone report` end to end, and the page in Chromium."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
from pathlib import Path

import cv2
import numpy as np
import pytest
from typer.testing import CliRunner

from clone import metrics, report
from clone.cli.main import app
from pose_io import BODY15, InputError, PoseTrack, measures
from pose_io.draw import draw_pose

SIZE = 64  # reference frames are SIZE x SIZE
T = 32

_STAND = {
    "nose": (32, 12), "neck": (32, 18), "r_shoulder": (27, 18), "r_elbow": (25, 27), "r_wrist": (24, 35),
    "l_shoulder": (37, 18), "l_elbow": (39, 27), "l_wrist": (40, 35), "mid_hip": (32, 36), "r_hip": (29, 36),
    "r_knee": (29, 46), "r_ankle": (29, 56), "l_hip": (35, 36), "l_knee": (35, 46), "l_ankle": (35, 56),
}  # fmt: skip


def walk(frames: int = T, scale: float = 1.0, size: int = SIZE) -> PoseTrack:
    """A body15 figure swinging its arms and stepping in place, in a size x size image at 30 fps."""
    base = np.array([_STAND[n] for n in BODY15.joints], dtype=np.float64)
    t = np.arange(frames)[:, None]
    joints = np.repeat(base[None], frames, axis=0)
    joints[:, BODY15.indices(["r_wrist", "l_wrist"]), 0] += 4 * np.sin(t / 3)
    joints[:, BODY15.index("r_ankle"), 1] -= np.clip(3 * np.sin(t / 2), 0, None)[:, 0]
    joints = (joints - [32, 56]) * scale + [size / 2, size * 56 / 64]
    return PoseTrack(joints, np.ones(joints.shape[:2]), 30.0, (size, size), "body15")


def frame_of(joints: np.ndarray, size: int = SIZE) -> np.ndarray:
    img = np.full((size, size, 3), (70, 80, 100), dtype=np.uint8)
    return draw_pose(img, joints, BODY15, thickness=2)


def make_methods(
    frames: int = 12, with_frames: bool = True
) -> tuple[dict, report.DriverInfo, report.GroundTruth]:
    driver = walk(frames, 0.8)
    truth = walk(frames)
    ref = measures.reference_limb_lengths(truth.joints)
    height = measures.skeleton_height(truth.joints)
    at = report.still_indices(frames, 3)
    methods = {}
    for name, label, shift in (("global-scale", "Global scaling", 3.0), ("retarget", "Retargeted", 0.0)):
        track = truth.replace(joints=truth.joints + [shift, 0])
        scores = metrics.evaluate_track(track, ref, height, truth)
        if with_frames:
            pred = [frame_of(j) for j in track.joints]
            scores = scores.merged(
                metrics.frame_scores(pred, [frame_of(j) for j in truth.joints], truth.joints)
            )
        stills = {t: frame_of(track.joints[t]) for t in at}
        methods[name] = report.MethodResult(
            label, track, scores, stills, {t: track.joints[t] for t in at}, "x"
        )
    info = report.DriverInfo(driver, "drv/poses.npz", "ref_model.pt", None)
    gt = report.GroundTruth("gt/poses", "gt/frames", {t: frame_of(truth.joints[t]) for t in at},
                            {t: truth.joints[t] for t in at})  # fmt: skip
    return methods, info, gt


def write_video(path: Path, frames: int = 12) -> Path:
    from pose_io.video import VideoWriter

    with VideoWriter(path, fps=30) as video:
        for j in walk(frames).joints:
            video.write(report.side_by_side([frame_of(j), frame_of(j)], ["a", "b"], SIZE))
    return path


# ------------------------------------------------------------------------------------------ folder rules


def test_report_dir_rules(tmp_path):
    methods, info, gt = make_methods(with_frames=False)
    plain = tmp_path / "plain"
    plain.mkdir()
    (plain / "keep.txt").write_text("mine")
    with pytest.raises(InputError, match="not made by `clone report`"):
        report.write_report(plain, methods, info, gt, overwrite=True)
    assert (plain / "keep.txt").read_text() == "mine" and len(list(plain.iterdir())) == 1
    afile = tmp_path / "afile"
    afile.write_text("x")
    with pytest.raises(InputError, match="not a report folder"):
        report.write_report(afile, methods, info, gt, overwrite=True)

    out = tmp_path / "rep"
    page = report.write_report(out, methods, info, gt)
    assert page == out / "report.html" and (out / report.MARKER).is_file()
    assert (out.stat().st_mode & 0o055) == 0o055  # readable by others, like any other output
    with pytest.raises(InputError, match="--overwrite"):
        report.write_report(out, methods, info, gt)
    (out / "old.txt").write_text("old")
    report.write_report(out, methods, info, gt, overwrite=True)
    assert not (out / "old.txt").exists() and (out / "report.html").is_file()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile", "plain", "rep"]  # no temp folders left


def test_failed_report_leaves_nothing(tmp_path):
    methods, info, gt = make_methods(with_frames=False)
    bad = {**methods, "retarget": report.MethodResult("R", methods["retarget"].poses, methods["retarget"].scores,
                                                      {99: np.zeros((8, 8, 3), np.uint8)})}  # fmt: skip
    bad["global-scale"] = report.MethodResult("G", methods["global-scale"].poses, methods["global-scale"].scores,
                                              {99: np.zeros((8, 8, 3), np.uint8)})  # fmt: skip
    with pytest.raises(ValueError, match="past the driver"):
        report.write_report(tmp_path / "rep", bad, info, gt)
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------------------------------ contents


def test_report_files_numbers_and_page(tmp_path):
    methods, info, gt = make_methods()
    video = write_video(tmp_path / "v.mp4")
    out = tmp_path / "rep"
    page_path = report.write_report(out, methods, info, gt, video=video)
    names = {p.name for p in out.iterdir()}
    stills = sorted(n for n in names if n.startswith("still_"))
    assert names == {".clone2d-report", "report.html", "metrics.json", "side_by_side.mp4", "curves.png",
                     "summary.png", *stills}  # fmt: skip
    assert stills == [f"still_{t:05d}.png" for t in report.still_indices(12, 3)]

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
    assert gs["summary"]["pose_rmse_pct"] == pytest.approx(
        3.0 / measures.skeleton_height(walk(12).joints) * 100
    )
    assert all(len(v) == 12 for v in gs["per_frame"].values())
    assert doc["metrics"]["pose_mse"]["display_scale"] == 1000.0

    page = page_path.read_text()
    # every link is relative and points at a file of the folder
    links = re.findall(r'(?:src|href)="([^"]+)"', page)
    assert links and all("://" not in ln and not ln.startswith("/") for ln in links)
    assert all((out / ln).is_file() for ln in links)
    assert set(stills) | {"curves.png", "summary.png", "side_by_side.mp4", "metrics.json"} <= set(links)
    assert "<video controls muted loop playsinline" in page and "<script" not in page
    # retargeted poses equal the truth: it holds the better pose error, highlighted; PSNR inf shown as ∞
    row = re.search(r"Joint RMSE</td>(.*?)</tr>", page).group(1)
    cells = re.findall(r"<td([^>]*)>([^<]*)</td>", row)[1:]
    assert cells[0] == ("", f"{gs['summary']['pose_rmse_pct']:.3g}") and cells[1] == (' class="best"', "0")
    assert re.search(r"PSNR \(frame\)</td>.*?<td class=\"best\">∞</td>", page)
    # per-limb breakdown: the shifted copy has the same limb lengths, so no limb has a better method
    limbs = re.search(r"Limb-length error per limb.*?</table>", page).group(0)
    assert limbs.count("<tr>") == 1 + len(BODY15.limbs) and 'class="best"' not in limbs

    for name in stills + ["curves.png", "summary.png"]:
        img = cv2.imread(str(out / name))
        assert img is not None and img.shape[0] > 50
    still = cv2.imread(str(out / stills[0]))
    # driver | 2 methods | ground truth, each scaled to 320 rows under a caption strip
    assert still.shape[0] == 320 + report.caption_height(320) and still.shape[1] >= 4 * 320 - 1


def test_best_methods_and_formatting():
    methods, _, _ = make_methods(with_frames=False)
    assert report.best_methods(methods, "pose_mse") == {"retarget"}
    assert report.best_methods(methods, "pck_0.1") == set()  # a tie highlights nobody
    differ = {n: report.MethodResult(m.label, m.poses, metrics.Scores(summary={"contact_share": i / 2}))
              for i, (n, m) in enumerate(methods.items())}  # fmt: skip
    assert report.best_methods(differ, "contact_share") == set()  # a description, not a quality
    assert report._fmt(float("inf")) == "∞" and report._fmt(float("nan")) == "–"
    assert report._fmt(0.0123, 1000.0) == "12.3"


def test_side_by_side_and_still_indices():
    a = np.zeros((30, 40, 3), np.uint8)
    b = np.full((61, 61, 3), 255, np.uint8)
    out = report.side_by_side([a, b], ["a", "b"], 61)
    assert report.caption_height(61) == 22
    assert out.shape == (61 + 22 + 1, 81 + 61, 3)  # 40x30 -> 81x61 and 61x61, one row padded to even
    assert out.shape[0] % 2 == 0 and out.shape[1] % 2 == 0
    assert report.still_indices(100, 4) == [20, 40, 60, 80]
    assert report.still_indices(2, 4) == [0, 1] and report.still_indices(0) == []
    panel = report.pose_panel(walk(1).joints[0], "body15", (SIZE, SIZE * 2), 32)
    assert panel.shape == (32, 16, 3) and panel.any()


# ------------------------------------------------------------------------------------------ `clone report`


@pytest.fixture
def tiny_models(tmp_path):
    """A reference model with a tiny untrained generator on a 32² canvas of 64² frames, and tiny
    untrained retargeting weights: the run is real, the pictures are noise."""
    import torch

    from clone.canvas import full_frame_canvas
    from clone.networks import GeneratorConfig, build_generator
    from clone.reference_model import ReferenceModel, save_reference_model
    from retarget.checkpoint import save_checkpoint
    from retarget.global_scale import scale_stats
    from retarget.model import NetworkConfig, RetargetNet
    from retarget.preprocess import NormStats

    torch.manual_seed(0)
    reference = walk(T)
    config = GeneratorConfig(base_channels=4, depth=3, max_channels=8)
    net = build_generator("unet", config)
    model = ReferenceModel(
        generator_name="unet", generator_config=config, generator_state=net.state_dict(),
        canvas=full_frame_canvas((SIZE, SIZE), 32), scale_stats=scale_stats(reference.joints, BODY15),
        reference_track=reference, track_summary={},
    )  # fmt: skip
    model_path = save_reference_model(model, tmp_path / "ref.pt")
    small = NetworkConfig(motion_channels=(30, 16, 16, 16), body_channels=(28, 8, 8, 8),
                          view_channels=(28, 8, 8, 8), decoder_channels=(16, 16, 30))  # fmt: skip
    weights = save_checkpoint(tmp_path / "w.pt", RetargetNet(small).eval(),
                              NormStats(np.zeros((15, 2)), np.full((15, 2), 20.0)))  # fmt: skip
    return model_path, weights


def write_gt(tmp_path: Path, frames: int = T, size: int = SIZE) -> tuple[Path, Path]:
    from pose_io.writers import write_track

    truth = walk(frames, size=size)
    poses = write_track(truth, tmp_path / "gt_poses.npz")
    folder = tmp_path / "gt_frames"
    folder.mkdir()
    for t, j in enumerate(truth.joints):
        cv2.imwrite(str(folder / f"frame_{t:04d}.png"), cv2.cvtColor(frame_of(j, size), cv2.COLOR_RGB2BGR))
    return poses, folder


def test_make_report_end_to_end(tmp_path, tiny_models):
    from pose_io.video import read_frames
    from pose_io.writers import write_track

    model_path, weights = tiny_models
    driver = write_track(walk(T, 0.8), tmp_path / "driver.npz")
    gt_poses, gt_frames = write_gt(tmp_path)
    run = report.make_report(driver, tmp_path / "rep", model_path=model_path, gt_poses=gt_poses,
                             gt_frames=gt_frames, weights=weights)  # fmt: skip
    assert run.page.is_file() and run.frames == T
    assert set(run.summary) == {"global-scale", "retarget"}
    for summary in run.summary.values():
        assert set(summary) == set(metrics.METRICS)  # every measure, ground-truth ones included
        assert 0.0 <= summary["ssim"] <= 1.0 and np.isfinite(summary["psnr"])
    video = read_frames(tmp_path / "rep" / "side_by_side.mp4")
    # driver | global scaling | retargeted | ground truth: the 32² canvas shown at 256 rows under a caption
    assert video.num_frames == T and video.size == (4 * 256, 256 + report.caption_height(256))
    doc = json.loads((tmp_path / "rep" / "metrics.json").read_text())
    assert doc["ground_truth"] == {"poses": str(gt_poses), "frames": str(gt_frames)}
    assert doc["driver_baseline"]["summary"]["limb_error_pct"] >= 0.0


def test_cli_report_and_ground_truth_mismatches(tmp_path, tiny_models):
    from pose_io.writers import write_track

    model_path, weights = tiny_models
    driver = write_track(walk(T, 0.8), tmp_path / "driver.npz")
    runner = CliRunner()
    base = ["report", str(driver), "--model", str(model_path), "--weights", str(weights), "--device", "cpu"]

    short = tmp_path / "short"
    short.mkdir()
    poses, frames = write_gt(short, frames=T - 2)
    result = runner.invoke(app, [*base, "--out", str(tmp_path / "a"), "--gt-frames", str(frames)])
    assert result.exit_code == 2 and f"{T - 2} ground-truth frames, the driver has {T}" in result.output
    result = runner.invoke(app, [*base, "--out", str(tmp_path / "a"), "--gt-poses", str(poses)])
    assert result.exit_code == 2 and f"have {T - 2} frames, the driver has {T}" in result.output
    big = tmp_path / "big"
    big.mkdir()
    _, frames = write_gt(big, size=SIZE + 16)
    result = runner.invoke(app, [*base, "--out", str(tmp_path / "a"), "--gt-frames", str(frames)])
    assert (
        result.exit_code == 2
        and "ground-truth frames are 80x80, the reference model's frames are 64x64" in (result.output)
    )
    assert not (tmp_path / "a").exists()

    result = runner.invoke(app, [*base, "--out", str(tmp_path / "a")])
    assert result.exit_code == 0, result.output
    assert "wrote" in result.output and (tmp_path / "a" / "report.html").is_file()
    doc = json.loads((tmp_path / "a" / "metrics.json").read_text())
    assert doc["ground_truth"] is None and "ssim" not in doc["methods"]["retarget"]["summary"]
    result = runner.invoke(app, [*base, "--out", str(tmp_path / "a")])
    assert result.exit_code == 2 and "--overwrite" in result.output


# ------------------------------------------------------------------------------------------ browser

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
    report.write_report(out, methods, info, gt, video=write_video(tmp_path / "v.mp4"))
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
    assert check["images"] == 2 + len(report.still_indices(12, 3)) and check["bad"] == []
    assert check["videos"] == [{"src": "side_by_side.mp4", "w": 2 * SIZE, "h": SIZE + report.caption_height(SIZE),
                                  "error": None}]  # fmt: skip
    shot = tmp_path / "shot.png"
    subprocess.run([*args, f"--screenshot={shot}", (out / "report.html").as_uri()], capture_output=True, check=False,
                   timeout=120)  # fmt: skip
    image = cv2.imread(str(shot))
    assert image is not None and image.shape[:2] == (900, 1366) and image.std() > 10  # something was drawn
