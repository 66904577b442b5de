"""Detailed pose maps end to end: a reference with face, hands and feet trains a body31 model; a driver's details
ride on the retargeted body; models without details (--no-details, files before them) drive as before."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from clone.cli.main import app
from clone.drive.poses import drive_poses, read_driver
from clone.model.reference import load_reference_model
from clone.runtime.pose_maps import draw_pose_maps
from pose_io.details import PARENT_BONES
from pose_io.layouts import BODY15, BODY31
from pose_io.track import PoseTrack
from pose_io.writers import write_track
from tests.clone.train_ref.helpers import (  # noqa: F401 (_restore_threads is an autouse fixture)
    _restore_threads,
    figure_track,
    one_line_error,
    train_args,
    write_reference,
)


def with_details(track: PoseTrack, seed: int = 0) -> PoseTrack:
    """The figure with detail points a few pixels from the end of their parent bones."""
    body = track.joints
    joints = np.full((track.num_frames, len(BODY31), 2), np.nan, np.float32)
    joints[:, :15] = body
    rng = np.random.default_rng(seed)
    for name, (_a, b) in PARENT_BONES.items():
        joints[:, BODY31.index(name)] = body[:, BODY15.index(b)] + rng.normal(0, 2, 2)
    conf = np.ones(joints.shape[:2], np.float32)
    return PoseTrack(joints, conf, track.fps, track.image_size, "body31")


@pytest.fixture
def reference(tmp_path: Path) -> tuple[Path, Path]:
    track = with_details(figure_track(24))
    _poses, frames = write_reference(tmp_path / "ref", track.to_layout("body15"))
    npz = write_track(track, tmp_path / "ref_poses.npz")
    return npz, frames


def train(reference: tuple[Path, Path], out: Path, *extra: str) -> PoseTrack:
    result = CliRunner().invoke(app, train_args(*reference, out, *extra))
    assert result.exit_code == 0, result.output
    return load_reference_model(out)


def test_a_detailed_reference_trains_a_body31_model_whose_drives_carry_the_drivers_details(reference, tmp_path):
    model = train(reference, tmp_path / "ref.pt")
    assert model.pose_layout == "body31"
    driver_track = with_details(figure_track(30, width=160, height=120, scale=0.7, phase=5.0, fps=12.0), seed=1)
    driver_path = write_track(driver_track, tmp_path / "drv.npz")
    driver = read_driver(driver_path, layout=model.pose_layout)
    assert driver.layout == "body31" and np.isfinite(driver.joints).all()
    for method in ("global-scale", "retarget"):
        driven, _ = drive_poses(driver, model, method)
        assert driven.layout == "body31" and np.isfinite(driven.joints).all(), method
        # Each detail sits off its parent joint as the driver's does, at the scale of the driven bone.
        for name, (a, b) in PARENT_BONES.items():
            i, pa, pb = BODY31.index(name), BODY15.index(a), BODY15.index(b)
            src = np.linalg.norm(driver.joints[:, i] - driver.joints[:, pb], axis=-1)
            dst = np.linalg.norm(driven.joints[:, i] - driven.joints[:, pb], axis=-1)
            ratio = (np.linalg.norm(driven.joints[:, pb] - driven.joints[:, pa], axis=-1)
                     / np.linalg.norm(driver.joints[:, pb] - driver.joints[:, pa], axis=-1))
            np.testing.assert_allclose(dst, src * ratio, rtol=1e-3, atol=1e-3)
    maps = np.concatenate(list(draw_pose_maps(model, driven)))
    bare = np.concatenate(list(draw_pose_maps(model, driven.to_layout("body15"))))
    assert (maps != bare).any()  # the details are drawn
    out = tmp_path / "out.mp4"
    poses_out = tmp_path / "driven.npz"
    result = CliRunner().invoke(app, ["drive", str(driver_path), "--out", str(out), "--model", str(tmp_path / "ref.pt"),
                                      "--threads", "1", "--poses-out", str(poses_out)])
    assert result.exit_code == 0, result.output
    from pose_io.readers import read_track

    assert out.stat().st_size > 0 and read_track(poses_out).layout == "body15"  # the network's joints


def test_no_details_trains_a_body15_model_and_resume_keeps_the_choice(reference, tmp_path):
    out = tmp_path / "ref.pt"
    model = train(reference, out, "--no-details")
    assert model.pose_layout == "body15"
    driver = read_driver(write_track(with_details(figure_track(12)), tmp_path / "drv.npz"), layout="body31")
    driven, _ = drive_poses(driver, model, "global-scale")
    assert driven.layout == "body15"
    result = CliRunner().invoke(app, train_args(*reference, out, "--resume", "--details"))
    assert "--details: the model's pose maps are body15 alone; cannot resume so" in one_line_error(result)
    result = CliRunner().invoke(app, train_args(*reference, out, "--resume", "--no-details"))
    assert result.exit_code == 0, result.output
    assert load_reference_model(out).pose_layout == "body15"
