"""train_ref.data: reading and checking the reference's poses and frames, and what is stored about them."""

from __future__ import annotations

import numpy as np
import pytest
from typer.testing import CliRunner

from clone.cli.main import app
from clone.model.reference import load_reference_model
from pose_io.writers import write_track
from tests.clone.train_ref.helpers import (
    OFFICIAL_WEIGHTS,
    figure_track,
    one_line_error,
    render_figure,
    train_args,
    write_reference,
)


def test_video_reference_uses_the_video_fps(tmp_path):
    from pose_io.video_out import VideoWriter

    track = figure_track(20, width=96, height=72, fps=25.0)
    poses = write_track(track.replace(fps=10.0), tmp_path / "poses.npz")
    video = tmp_path / "ref.mp4"
    with VideoWriter(video, fps=15.0) as writer:
        for frame in render_figure(track):
            writer.write(frame)
    out = tmp_path / "ref.pt"
    result = CliRunner().invoke(app, train_args(poses, video, out))
    assert result.exit_code == 0, result.output
    model = load_reference_model(out)
    assert model.reference_track.fps == pytest.approx(15.0) and model.reference_track.num_frames == 20


def test_mismatched_counts_error_or_trim(tmp_path):
    track = figure_track(24)
    poses, frames = write_reference(tmp_path / "ref", track, render_figure(track)[:20])
    out = tmp_path / "ref.pt"
    line = one_line_error(CliRunner().invoke(app, train_args(poses, frames, out)))
    assert "24 poses" in line and "20 frames" in line and "--align trim" in line
    assert not out.exists()
    result = CliRunner().invoke(app, train_args(poses, frames, out, "--align", "trim"))
    assert result.exit_code == 0, result.output
    assert load_reference_model(out).reference_track.num_frames == 20


def test_empty_frames_folder_and_missing_poses(reference, tmp_path):
    poses, _ = reference
    empty = tmp_path / "empty"
    empty.mkdir()
    out = tmp_path / "ref.pt"
    assert "no image files" in one_line_error(CliRunner().invoke(app, train_args(poses, empty, out)))
    _, frames = reference
    assert "no such file or folder" in one_line_error(CliRunner().invoke(app, train_args(tmp_path / "nope", frames, out)))
    assert not out.exists()


def test_frames_without_usable_pose_are_skipped_and_counted(tmp_path):
    track = figure_track(24)
    frames = render_figure(track)
    joints = track.joints.copy()
    joints[[3, 4, 10], :8] = np.nan  # 7 of 15 joints left: below the default minimum of 10
    track = track.replace(joints=joints)
    poses, frame_dir = write_reference(tmp_path / "ref", track, frames)
    out = tmp_path / "ref.pt"
    result = CliRunner().invoke(app, train_args(poses, frame_dir, out))
    assert result.exit_code == 0, result.output
    assert "3 skipped" in result.output
    summary = load_reference_model(out).track_summary
    assert summary["usable_frames"] == 21 and summary["skipped_frames"] == 3


@pytest.mark.skipif(not OFFICIAL_WEIGHTS.is_file(), reason="the authors' retargeting weights are not present")
def test_reference_codes_are_stored_with_retargeting_weights(tmp_path):
    poses, frames = write_reference(tmp_path / "ref", figure_track(64))
    out = tmp_path / "ref.pt"
    result = CliRunner().invoke(app, train_args(poses, frames, out, "--weights", str(OFFICIAL_WEIGHTS)))
    assert result.exit_code == 0, result.output
    model = load_reference_model(out)
    assert model.reference_codes is not None and model.reference_codes["body"].shape == (16,)
    assert model.codes_weights is not None and len(model.codes_weights) == 64
    assert model.codes_weights_path == str(OFFICIAL_WEIGHTS.resolve())


def test_pose_jitter_moves_the_pose_maps_and_not_the_frames():
    import torch

    from clone.train_ref import AugmentConfig, TrainConfig
    from clone.train_ref.data import ReferenceData

    track = figure_track(6, width=64, height=64)
    frames = np.random.default_rng(0).integers(0, 255, (6, 64, 64, 3), dtype=np.uint8)
    data = ReferenceData(frames, track.joints, np.ones(6, bool), 64, layout="body15", faces=False)
    assert data.height is not None and data.height > 20
    idx = np.array([2, 3])
    plain = data.batch(idx)
    offsets = np.zeros((2, 15, 2))
    offsets[1, 4] = (5.0, -3.0)  # the second sample's right wrist
    moved = data.batch(idx, offsets)
    assert torch.equal(plain["frame_cur"], moved["frame_cur"]) and torch.equal(plain["frame_prev"], moved["frame_prev"])
    assert torch.equal(plain["pose_cur"][0], moved["pose_cur"][0])
    assert not torch.equal(plain["pose_cur"][1], moved["pose_cur"][1])
    assert not torch.equal(plain["pose_prev"][1], moved["pose_prev"][1])
    assert TrainConfig(augment=AugmentConfig(pose_jitter=0.02)).augment.pose_jitter == 0.02
    assert AugmentConfig().pose_jitter == 0.0


def test_mirror_flips_frames_plate_and_face_and_swaps_the_pose_maps_sides():
    import torch

    from clone.model.canvas import render_pose_map
    from clone.train_ref.data import ReferenceData
    from pose_io.layouts import get_layout

    layout = get_layout("body31")
    track = figure_track(6, width=64, height=64).to_layout("body31")
    joints = track.joints.copy()
    joints[:, layout.index("nose")] += (6.0, 0.0)  # a face off the body's axis, so that mirroring moves it
    frames = np.random.default_rng(0).integers(0, 255, (6, 64, 64, 3), dtype=np.uint8)
    plate = np.random.default_rng(1).integers(0, 255, (64, 64, 3), dtype=np.uint8)
    data = ReferenceData(frames, joints, np.ones(6, bool), 64, plate=plate, layout="body31")
    idx = np.array([2, 3])
    plain, flipped = data.batch(idx), data.batch(idx, mirror=np.array([False, True]))
    for key in ("pose_cur", "pose_prev", "frame_cur", "frame_prev", "plate", "face"):
        assert torch.equal(plain[key][0], flipped[key][0]), key
    for key in ("frame_cur", "frame_prev", "plate", "face"):
        assert torch.equal(flipped[key][1], plain[key][1].flip(-1)), key
    assert not torch.equal(flipped["face"][1], plain["face"][1])
    # the flipped person's right wrist is where her left one was, mirrored
    mirrored = data.frame_joints(3, mirrored=True)
    left, right = layout.index("l_wrist"), layout.index("r_wrist")
    np.testing.assert_allclose(mirrored[right], (63.0 - joints[3, left, 0], joints[3, left, 1]))
    np.testing.assert_allclose(data.frame_joints(3, True)[layout.mirror] * (-1, 1) + (63.0, 0), joints[3])
    expected = torch.from_numpy(render_pose_map(mirrored, 64, layout)).permute(2, 0, 1).float() / 127.5 - 1.0
    torch.testing.assert_close(flipped["pose_cur"][1], expected)
    # a pose map is not the flipped image of the other: the sides' colours are swapped
    assert not torch.equal(flipped["pose_cur"][1], plain["pose_cur"][1].flip(-1))


def test_a_run_with_mirror_trains(reference, tmp_path):
    from clone.train_ref import AugmentConfig, TrainConfig, train_reference

    poses, frames = reference
    config = TrainConfig(size=32, augment=AugmentConfig(mirror=1.0))
    result = train_reference(poses, frames, tmp_path / "m.pt", config=config, steps=2, device="cpu")
    assert result.steps == 2
    assert load_reference_model(tmp_path / "m.pt").training["config"]["augment"]["mirror"] == 1.0


def test_a_dropped_limb_blacks_out_the_samples_exemplar_along_it_and_nothing_else():
    import torch

    from clone.model.exemplar import LIMBS, choose_bank
    from clone.train_ref import AugmentConfig
    from clone.train_ref.data import ReferenceData

    track = figure_track(40, width=64, height=64)
    frames = np.full((40, 64, 64, 3), 180, np.uint8)
    data = ReferenceData(frames, track.joints, np.ones(40, bool), 64, layout="body15", faces=False)
    data.set_exemplars(choose_bank(frames, track.joints, np.ones(40, bool), max_count=8), gap=13)
    idx = np.array([20, 21])
    plain = data.batch(idx)
    dropped = data.batch(idx, exemplar_drop=np.array([-1, 3]))
    assert torch.equal(plain["exemplar_cur"][0], dropped["exemplar_cur"][0])
    black = (dropped["exemplar_cur"][1] == -1).all(0)  # [S, S]
    x, y = np.round(track.joints[21, LIMBS[3][1]]).astype(int)  # the left knee
    assert bool(black[y, x]) and bool((dropped["exemplar_prev"][1] == -1).all(0).any())
    assert not bool((plain["exemplar_cur"][1] == -1).all(0).any()) and float(black.float().mean()) < 0.2
    assert AugmentConfig().exemplar_drop == 0.25
