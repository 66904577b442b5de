"""train-ref: data checks, augmentation, the model file, resuming. Tiny synthetic performers, 32² canvases."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest
import torch
from typer.testing import CliRunner

from clone.cli.main import app
from clone.reference_model import KIND, load_reference_model, preview_path, state_path
from clone.train_ref import (
    AugmentConfig,
    TrainConfig,
    Trainer,
    degrade_previous,
    random_affines,
    to_tensor,
    warp_batch,
)
from pose_io import BODY15, PoseTrack
from pose_io.writers import write_track

OFFICIAL_WEIGHTS = Path(__file__).resolve().parents[3] / "shared" / "official_2dmr" / "weights" / "pretrained_full.pth"


# ------------------------------------------------------------------------------------------------ synthetic data


def figure_track(frames: int = 24, width: int = 96, height: int = 72, scale: float = 1.0, phase: float = 0.0,
                 fps: float = 25.0) -> PoseTrack:
    """A body15 figure swinging its arms and legs while drifting sideways."""
    base = np.array(
        [[0, -0.62], [0, -0.5], [-0.12, -0.48], [-0.16, -0.3], [-0.17, -0.12], [0.12, -0.48], [0.16, -0.3],
         [0.17, -0.12], [0, 0], [-0.07, 0], [-0.08, 0.2], [-0.08, 0.4], [0.07, 0], [0.08, 0.2], [0.08, 0.4]])
    t = np.arange(frames)[:, None] + phase
    j = np.repeat(base[None], frames, axis=0)
    swing = np.sin(2 * np.pi * t[:, 0] / 12.0)
    for side, sign in (("r", 1.0), ("l", -1.0)):
        j[:, BODY15.index(f"{side}_wrist"), 0] += sign * 0.15 * swing
        j[:, BODY15.index(f"{side}_ankle"), 0] -= sign * 0.1 * swing
    xy = j * 0.6 * height * scale
    xy[..., 0] += width / 2 + 0.15 * width * np.sin(2 * np.pi * t / 40.0)
    xy[..., 1] += height * 0.52
    return PoseTrack(xy.astype(np.float32), np.ones(xy.shape[:2], np.float32), fps, (width, height), "body15")


def render_figure(track: PoseTrack) -> list[np.ndarray]:
    """Frames of ``track``: coloured limbs, torso and head over a checked background, [H, W, 3] uint8."""
    w, h = track.image_size
    yy, xx = np.mgrid[0:h, 0:w]
    background = np.stack([80 + 0 * xx, 120 + 40 * yy // h, 100 + 20 * ((xx // 6 + yy // 6) % 2)], -1)
    frames = []
    for pose in track.joints:
        img = background.astype(np.uint8)

        def at(name: str, p: np.ndarray = pose) -> tuple[int, int]:
            return tuple(round(float(v)) for v in p[BODY15.index(name)])

        torso = np.array([at("r_shoulder"), at("l_shoulder"), at("l_hip"), at("r_hip")], np.int32)
        cv2.fillConvexPoly(img, torso, (220, 180, 40))
        for a, b in BODY15.limbs:
            colour = (40, 60, 190) if "hip" in a or "knee" in a else (200, 40, 40)
            cv2.line(img, at(a), at(b), colour, 3)
        cv2.circle(img, at("nose"), 5, (240, 200, 170), -1)
        frames.append(img)
    return frames


def write_reference(folder: Path, track: PoseTrack, frames: list[np.ndarray] | None = None) -> tuple[Path, Path]:
    """Poses as an OpenPose folder and frames as PNGs; returns (poses, frames folder)."""
    frames = render_figure(track) if frames is None else frames
    frame_dir = folder / "frames"
    frame_dir.mkdir(parents=True)
    for i, f in enumerate(frames):
        cv2.imwrite(str(frame_dir / f"{i:04d}.png"), cv2.cvtColor(f, cv2.COLOR_RGB2BGR))
    poses = write_track(track, folder / "poses")
    return poses, frame_dir


def train_args(poses: Path, frames: Path, out: Path, *extra: str, steps: int = 3) -> list[str]:
    return ["train-ref", str(poses), str(frames), "--out", str(out), "--size", "32", "--steps", str(steps),
            "--threads", "1", "--device", "cpu", *extra]


def one_line_error(result) -> str:
    assert result.exit_code == 2, result.output
    lines = [line for line in result.output.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), result.output
    return lines[0]


@pytest.fixture
def reference(tmp_path: Path) -> tuple[Path, Path]:
    return write_reference(tmp_path / "ref", figure_track())


@pytest.fixture(autouse=True)
def _restore_threads():
    before = torch.get_num_threads()
    yield
    torch.set_num_threads(before)


# ------------------------------------------------------------------------------------------------ CLI


def test_train_ref_writes_one_model_state_and_preview(reference, tmp_path):
    poses, frames = reference
    out = tmp_path / "m" / "ref.pt"
    result = CliRunner().invoke(app, train_args(poses, frames, out))
    assert result.exit_code == 0, result.output
    assert out.is_file() and state_path(out).is_file() and preview_path(out).is_file()
    raw = torch.load(out, map_location="cpu", weights_only=True)
    assert raw["kind"] == KIND and raw["format_version"] == 1
    model = load_reference_model(out)
    assert model.canvas.size == 32 and model.canvas.image_size == (96, 72)
    assert model.generator_config.depth == 3 and model.temporal
    assert model.training["steps"] == 3
    assert model.reference_track.num_frames == 24 and model.reference_track.layout == "body15"
    assert model.scale_stats is not None and model.scale_stats.foot_close > 0
    assert model.track_summary["usable_frames"] == 24
    preview = cv2.imread(str(preview_path(out)))
    assert preview.shape[1] == 3 * 32 and preview.shape[0] % 32 == 0
    # The stored generator rebuilds and runs without any flags.
    net = model.build_generator()
    assert net(torch.zeros(1, 6, 32, 32)).shape == (1, 3, 32, 32)


def test_default_out_is_ref_model_in_the_current_folder(reference, tmp_path, monkeypatch):
    poses, frames = reference
    monkeypatch.chdir(tmp_path)
    args = ["train-ref", str(poses), str(frames), "--size", "32", "--steps", "1", "--threads", "1"]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    assert (tmp_path / "ref_model.pt").is_file()
    # Never replaced without --resume or --overwrite.
    before = (tmp_path / "ref_model.pt").read_bytes()
    assert "already exists" in one_line_error(CliRunner().invoke(app, args))
    assert (tmp_path / "ref_model.pt").read_bytes() == before
    assert CliRunner().invoke(app, args + ["--overwrite"]).exit_code == 0


def test_resume_continues_the_step_count(reference, tmp_path):
    poses, frames = reference
    out = tmp_path / "ref.pt"
    assert CliRunner().invoke(app, train_args(poses, frames, out)).exit_code == 0
    args = ["train-ref", str(poses), str(frames), "--out", str(out), "--steps", "5", "--threads", "1", "--resume"]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    assert load_reference_model(out).training["steps"] == 5
    assert "--size 64 differs" in one_line_error(CliRunner().invoke(app, args + ["--size", "64"]))
    missing = ["train-ref", str(poses), str(frames), "--out", str(tmp_path / "none.pt"), "--resume"]
    assert "nothing to resume" in one_line_error(CliRunner().invoke(app, missing))


def test_resumed_run_equals_an_uninterrupted_one(reference, tmp_path):
    poses, frames = reference
    straight, split = tmp_path / "straight.pt", tmp_path / "split.pt"
    assert CliRunner().invoke(app, train_args(poses, frames, straight, steps=4)).exit_code == 0
    assert CliRunner().invoke(app, train_args(poses, frames, split, steps=2)).exit_code == 0
    more = ["train-ref", str(poses), str(frames), "--out", str(split), "--steps", "4", "--threads", "1", "--resume"]
    assert CliRunner().invoke(app, more).exit_code == 0
    a, b = load_reference_model(straight), load_reference_model(split)
    assert a.training["steps"] == b.training["steps"] == 4
    for key, value in a.generator_state.items():
        torch.testing.assert_close(b.generator_state[key], value, rtol=0, atol=0)


def test_video_reference_uses_the_video_fps(tmp_path):
    from pose_io.video import VideoWriter

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
    assert "does not exist" in one_line_error(CliRunner().invoke(app, train_args(tmp_path / "nope", frames, out)))
    assert not out.exists()


def test_bad_options_are_one_line_errors(reference, tmp_path):
    poses, frames = reference
    out = tmp_path / "ref.pt"
    assert "power of two" in one_line_error(CliRunner().invoke(app, train_args(poses, frames, out, "--size", "100")))
    assert "--align" in one_line_error(CliRunner().invoke(app, train_args(poses, frames, out, "--align", "pad")))
    assert "device" in one_line_error(CliRunner().invoke(app, train_args(poses, frames, out, "--device", "tpu")))
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


# ------------------------------------------------------------------------------------------------ pieces


def test_augmentation_warps_pose_maps_and_frames_identically():
    gen = torch.Generator().manual_seed(0)
    img = np.zeros((2, 32, 32, 3), dtype=np.uint8)
    img[:, 8:24, 12:20] = 255  # the same white block in the pose maps and the frames
    x = to_tensor(img)
    sample = {"pose_prev": x, "pose_cur": x, "frame_prev": x, "frame_cur": x,
              "has_prev": torch.tensor([True, True])}
    m = random_affines(2, 32, AugmentConfig(rotation_deg=10, scale=0.1, translate=0.1), gen)
    assert not torch.allclose(m[0], m[1])
    out = warp_batch(sample, m)
    assert not torch.allclose(out["pose_cur"], x)
    for key in ("pose_prev", "frame_prev", "frame_cur"):
        torch.testing.assert_close(out[key], out["pose_cur"])
    # The identity warp changes nothing.
    ident = torch.tensor([[[1.0, 0, 0], [0, 1.0, 0]]]).repeat(2, 1, 1)
    torch.testing.assert_close(warp_batch(sample, ident)["frame_cur"], x, atol=1e-5, rtol=0)


def test_previous_frame_is_zeros_without_one_and_when_dropped():
    gen = torch.Generator().manual_seed(0)
    prev = torch.rand(4, 3, 8, 8) * 2 - 1
    has = torch.tensor([True, False, True, True])
    out = degrade_previous(prev, has, AugmentConfig(), dropout=0.0, generator=gen)
    assert torch.equal(out[1], torch.zeros(3, 8, 8))
    assert (out[0] - prev[0]).abs().mean() < 0.3 and not torch.equal(out[0], prev[0])
    assert degrade_previous(prev, has, AugmentConfig(), dropout=1.0, generator=gen).abs().max() == 0


@pytest.mark.parametrize("source", ["real", "generated"])
def test_previous_input_sources(source):
    torch.manual_seed(0)
    config = TrainConfig(size=32, base_channels=8, disc_channels=8, prev_source=source, prev_dropout=0.0,
                         augment=AugmentConfig(prev_jitter=0.0, prev_noise=0.0))
    trainer = Trainer(config, torch.device("cpu"))
    x = torch.rand(3, 3, 32, 32) * 2 - 1
    sample = {"pose_prev": x.flip(0), "pose_cur": x, "frame_prev": x, "frame_cur": x,
              "has_prev": torch.tensor([True, True, False])}
    g_in, d_prev = trainer.previous_input(sample, torch.Generator().manual_seed(0))
    assert torch.equal(g_in[2], torch.zeros(3, 32, 32)) and torch.equal(d_prev[2], torch.zeros(3, 32, 32))
    if source == "real":
        torch.testing.assert_close(g_in[:2], x[:2])
    else:  # G's own frame for t-1, made from its pose map and no previous frame
        with torch.no_grad():
            expected = trainer.generate(sample["pose_prev"][:2], torch.zeros(2, 3, 32, 32))
        torch.testing.assert_close(d_prev[:2], expected)
        torch.testing.assert_close(g_in[:2], expected)
    losses = trainer.train_step(sample, g_in, d_prev)
    assert set(losses) == {"l1", "gan", "fm", "d"} and all(np.isfinite(v) for v in losses.values())


def test_trainer_steps_lower_l1_on_a_fixed_batch():
    torch.manual_seed(0)
    config = TrainConfig(size=32, base_channels=8, disc_channels=8, lr=1e-3)
    trainer = Trainer(config, torch.device("cpu"))
    rng = np.random.default_rng(0)
    batch = {k: torch.from_numpy(rng.uniform(-1, 1, (2, 3, 32, 32)).astype(np.float32))
             for k in ("pose_prev", "pose_cur", "frame_prev", "frame_cur")}
    first = trainer.train_step(batch, batch["frame_prev"])["l1"]
    for _ in range(4):
        last = trainer.train_step(batch, batch["frame_prev"])["l1"]
    assert last < first
    assert trainer.step_count == 5
