"""Videos straight in: `clone train-ref VIDEO` and `clone drive VIDEO` without an extract step; the driver's sound
kept in the output (--audio auto, none, FILE)."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from clone.cli.main import app
from pose_io import extract
from tests.clone.train_ref.helpers import (  # noqa: F401 (_restore_threads is an autouse fixture)
    _restore_threads,
    figure_track,
    one_line_error,
    train_args,
    write_reference,
)
from tests.pose_io.media import media_info, write_person_video, write_tone

pytest.importorskip("mediapipe")


@pytest.fixture(autouse=True)
def _cache_in_tmp(tmp_path, monkeypatch):
    monkeypatch.setenv("CLONE2D_CACHE", str(tmp_path / "cache"))


def cut(video: Path, out: Path, seconds: float, width: int) -> Path:
    """The first ``seconds`` of ``video``, scaled to ``width`` (sound kept), with the bundled ffmpeg."""
    import subprocess

    import imageio_ffmpeg

    subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-i", str(video), "-t", str(seconds), "-vf",
                    f"scale={width}:-2", "-c:v", "libx264", "-c:a", "aac", str(out)], check=True)
    return out


def test_train_ref_takes_a_real_video_alone(shared_dir, tmp_path):
    ref = cut(shared_dir / "real" / "ubc_91BjuE6irxS.mp4", tmp_path / "ref.mp4", 1.0, 208)
    model = tmp_path / "ref.pt"
    run = CliRunner().invoke(app, ["train-ref", str(ref), "--out", str(model), "--size", "32", "--steps", "2",
                                   "--threads", "1", "--device", "cpu"])
    assert run.exit_code == 0, run.output
    assert "on 30 frames" in run.output and model.is_file()


def test_a_driver_video_drives_and_its_sound_comes_along(trained, tmp_path, monkeypatch):
    tone = write_tone(tmp_path / "music.wav", 5.0)
    driver = write_person_video(tmp_path / "dance.mp4", frames=18, fps=12.0, audio=tone, size=160)
    common = ["--model", str(trained), "--threads", "1", "--device", "cpu", "--method", "none"]
    out = tmp_path / "out.mp4"
    run = CliRunner().invoke(app, ["drive", str(driver), "--out", str(out), *common])
    assert run.exit_code == 0, run.output
    assert "with the sound of" in run.output
    sound, duration = media_info(out)
    assert sound and abs(duration - 18 / 12.0) < 0.25

    def no_extraction(*args, **kwargs):
        raise AssertionError("extracted again")

    monkeypatch.setattr(extract, "extract_track", no_extraction)  # the second drive reads the cache
    silent = tmp_path / "silent.mp4"
    run = CliRunner().invoke(app, ["drive", str(driver), "--out", str(silent), "--audio", "none", *common])
    assert run.exit_code == 0, run.output
    assert media_info(silent)[0] is False
    other = tmp_path / "other.mp4"
    run = CliRunner().invoke(app, ["drive", str(driver), "--out", str(other), "--audio", str(tone), *common])
    assert run.exit_code == 0 and media_info(other)[0]
    line = one_line_error(CliRunner().invoke(app, ["drive", str(driver), "--out", str(tmp_path / "x.mp4"),
                                                   "--audio", str(silent), *common]))
    assert "no audio stream" in line and not (tmp_path / "x.mp4").exists()


def test_train_ref_needs_frames_when_the_poses_are_not_a_video(tmp_path):
    poses = tmp_path / "poses"
    poses.mkdir()
    line = one_line_error(CliRunner().invoke(app, ["train-ref", str(poses), "--out", str(tmp_path / "m.pt")]))
    assert "FRAMES" in line
