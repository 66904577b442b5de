"""Every walkthrough in examples/ runs here on tiny inputs, so none of them can rot."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def run(args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ)
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"  # the venv's `clone`
    result = subprocess.run(args, cwd=cwd, env=env, capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stdout[-2000:] + result.stderr[-2000:]
    return result


def test_retarget_openpose(shared_dir, tmp_path):
    examples = shared_dir / "openpose_examples"
    out = tmp_path / "out"
    run(["bash", str(EXAMPLES / "retarget_openpose.sh"), str(examples / "tall_man"), str(examples / "small_man"),
         str(out)], tmp_path)
    data = np.load(out / "retargeted.npz")
    assert data["joints"].shape[0] == 135 and data["joints"].shape[1] == 15
    assert (out / "retargeted.mp4").stat().st_size > 0 and (out / "reference.mp4").stat().st_size > 0


def test_api_script(shared_dir, tmp_path):
    examples = shared_dir / "openpose_examples"
    result = run([sys.executable, str(EXAMPLES / "api.py"), str(examples / "tall_man"), str(examples / "small_man"),
                  str(tmp_path / "out")], tmp_path)
    assert "limb-length error" in result.stdout
    assert (tmp_path / "out" / "retargeted.npz").is_file()


def _synthetic_video(path: Path, role: str, character: str, yaw: float, frames: int) -> None:
    from clone.demo import demo_motions
    from clone.synth import get_character, render_performance
    from pose_io.video import VideoWriter

    skeleton, look, _ = get_character(character)
    images, _track, _meta = render_performance(demo_motions()[role], skeleton, look, yaw=yaw, size=160,
                                               frames=frames)
    with VideoWriter(path, fps=30.0) as video:
        for image in images:
            video.write(image)


def test_video_pipeline(tmp_path):
    pytest.importorskip("mediapipe")
    _synthetic_video(tmp_path / "ref.mp4", "reference", "tall_long_legs", 15.0, 36)
    _synthetic_video(tmp_path / "drv.mp4", "driver", "short_stocky", -30.0, 24)
    out = tmp_path / "out"
    run(["bash", str(EXAMPLES / "video_pipeline.sh"), "ref.mp4", "drv.mp4", str(out), "0.05"], tmp_path)
    assert (out / "result.mp4").stat().st_size > 0
    metrics = json.loads((out / "report" / "metrics.json").read_text())
    assert set(metrics["methods"]) >= {"retarget", "global-scale"}
