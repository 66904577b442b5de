"""Every walkthrough in examples/ runs here on tiny inputs, so none of them can rot."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.examples_support import EXAMPLES, write_people
from tests.examples_support import run_example as run

EXAMPLE_FRAMES = 45


@pytest.fixture(scope="module")
def openpose_examples(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Two OpenPose folders like the authors' examples (a tall and a small person), built here."""
    return write_people(tmp_path_factory.mktemp("people"), EXAMPLE_FRAMES)


def test_retarget_openpose(openpose_examples, tmp_path):
    out = tmp_path / "out"
    run(["bash", str(EXAMPLES / "retarget_openpose.sh"), str(openpose_examples / "tall_man"),
         str(openpose_examples / "small_man"), str(out)], tmp_path)
    data = np.load(out / "retargeted.npz")
    assert data["joints"].shape == (EXAMPLE_FRAMES, 15, 2)
    assert (out / "retargeted.mp4").stat().st_size > 0 and (out / "reference.mp4").stat().st_size > 0


def test_api_script(openpose_examples, tmp_path):
    result = run([sys.executable, str(EXAMPLES / "api.py"), str(openpose_examples / "tall_man"),
                  str(openpose_examples / "small_man"), str(tmp_path / "out")], tmp_path)
    assert "proportion error" in result.stdout
    assert np.load(tmp_path / "out" / "retargeted.npz")["joints"].shape == (EXAMPLE_FRAMES, 15, 2)


def _synthetic_video(path: Path, role: str, character: str, yaw: float, frames: int) -> None:
    from clone.demo import demo_motions
    from clone.synth import get_character, render_performance
    from pose_io.video_out import VideoWriter

    skeleton, look, _ = get_character(character)
    images, _track, _meta = render_performance(demo_motions()[role], skeleton, look, yaw=yaw, size=160,
                                               frames=frames)
    with VideoWriter(path, fps=30.0) as video:
        for image in images:
            video.write(image)


def test_video_pipeline(tmp_path, monkeypatch):
    pytest.importorskip("mediapipe")
    monkeypatch.setenv("CLONE2D_CACHE", str(tmp_path / "cache"))
    _synthetic_video(tmp_path / "ref.mp4", "reference", "tall_long_legs", 15.0, 36)
    _synthetic_video(tmp_path / "drv.mp4", "driver", "short_stocky", -30.0, 24)
    out = tmp_path / "out"
    run(["bash", str(EXAMPLES / "video_pipeline.sh"), "ref.mp4", "drv.mp4", str(out), "0.05"], tmp_path)
    assert (out / "result.mp4").stat().st_size > 0
    metrics = json.loads((out / "report" / "metrics.json").read_text())
    assert set(metrics["methods"]) >= {"retarget", "global-scale"}


def test_real_video(shared_dir, tmp_path, monkeypatch):
    """examples/real_video.sh on the first seconds of the real videos (cut here with the bundled ffmpeg)."""
    import subprocess

    monkeypatch.setenv("CLONE2D_CACHE", str(tmp_path / "cache"))
    import imageio_ffmpeg

    pytest.importorskip("mediapipe")
    real = tmp_path / "real"
    real.mkdir()
    for name, seconds in (("ubc_91BjuE6irxS.mp4", 1.5), ("dance_musepose.mp4", 1.0)):
        subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-i", str(shared_dir / "real" / name), "-t",
                        str(seconds), "-vf", "scale=-2:480", "-c:v", "libx264", "-c:a", "aac", str(real / name)],
                       check=True)
    out = tmp_path / "out"
    result = run(["bash", str(EXAMPLES / "real_video.sh"), str(real), str(out), "0.05", "64"], tmp_path)
    assert "with the sound of" in result.stdout + result.stderr
    for name in ("dance.mp4", "dance_global_scale.mp4", "report/report.html"):
        assert (out / name).stat().st_size > 0
    absent = run(["bash", str(EXAMPLES / "real_video.sh"), str(tmp_path / "nowhere"), str(out / "x")], tmp_path)
    assert absent.stdout.startswith("skipped:")
