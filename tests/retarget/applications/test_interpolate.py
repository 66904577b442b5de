"""Latent interpolation: the grid's shape, its corners, linearity of the blend, the command, and parity with the
authors' ``interpolate.py`` on their examples and weights (../shared)."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch
from typer.testing import CliRunner

from clone.cli.main import app
from pose_io import InputError
from pose_io.resample import resample
from pose_io.writers import write_track
from retarget.api import InferenceConfig, ReferenceCodes, Retargeter, load_retargeter
from retarget.applications.interpolate import (
    LatentCodes,
    blend_weights,
    grid_codes,
    grid_frames,
    interpolate_grid,
    parse_vary,
)
from retarget.network.model import NetworkConfig, RetargetNet, variant_config
from retarget.network.preprocess import PreprocessConfig
from tests.figures import tall_and_small

FRAMES = 48


@pytest.fixture(scope="module")
def retargeter() -> Retargeter:
    torch.set_num_threads(1)
    # the packaged weights; the grid decodes the encoders' motion codes, so its corners are retargeting
    # without motion-code refinement
    return load_retargeter(config=InferenceConfig(refine_steps=0))


@pytest.fixture(scope="module")
def people():
    return tall_and_small(FRAMES + 8)  # B is longer: the grid takes the shorter length


@pytest.fixture(scope="module")
def clips(people):
    return people["tall"].frames(0, FRAMES), people["small"]


def test_grid_has_steps_by_steps_cells_of_the_shorter_length(retargeter, clips):
    grid = interpolate_grid(retargeter, *clips, vary=("motion", "view"), steps=4)
    assert grid.poses.shape == (4, 4, FRAMES, 15, 2)
    assert (grid.rows, grid.cols, grid.kept) == ("motion", "view", "body")
    assert grid.image_size == clips[0].image_size and np.isfinite(grid.poses).all()
    np.testing.assert_allclose(grid.weights, [0, 1 / 3, 2 / 3, 1], atol=1e-7)
    short = interpolate_grid(retargeter, *clips, steps=2, frames=24)
    assert short.poses.shape[2] == 24


@pytest.mark.parametrize("vary", [("motion", "view"), ("motion", "body"), ("body", "view")])
def test_corners_are_plain_retargeting_with_a_and_b_codes(retargeter, clips, vary):
    a, b = clips[0], clips[1].frames(0, FRAMES)
    grid = interpolate_grid(retargeter, a, b, vary=vary, steps=3)
    codes = {"A": retargeter.reference_codes(a), "B": retargeter.reference_codes(b)}
    frame = codes["A"]  # every cell is drawn in A's frame
    for i, j in [(0, 0), (0, 2), (2, 0), (2, 2)]:
        source = {vary[0]: "AB"[i // 2], vary[1]: "AB"[j // 2]}
        who = {name: source.get(name, "A") for name in ("motion", "body", "view")}
        reference = ReferenceCodes(codes[who["body"]].body, codes[who["view"]].view, frame.placement,
                                   frame.image_size, frame.scale)
        expected = retargeter.retarget(a if who["motion"] == "A" else b, reference).joints
        np.testing.assert_allclose(grid.poses[i, j], expected, atol=2e-3)


def test_blended_codes_are_linear_and_the_third_attribute_is_a(retargeter):
    gen = torch.Generator().manual_seed(0)
    a, b = (LatentCodes(torch.randn(1, 128, 6, generator=gen), torch.randn(1, 16, 1, generator=gen),
                        torch.randn(1, 8, 1, generator=gen)) for _ in range(2))
    cells = grid_codes(a, b, "body", "motion", steps=5)
    w = blend_weights(5)
    for i in range(5):
        for j in range(5):
            k = i * 5 + j
            torch.testing.assert_close(cells.body[k], (1 - w[i]) * a.body[0] + w[i] * b.body[0])
            torch.testing.assert_close(cells.motion[k], (1 - w[j]) * a.motion[0] + w[j] * b.motion[0])
            assert torch.equal(cells.view[k], a.view[0])


def test_with_an_affine_decoder_the_grid_is_affine_in_the_weights(retargeter, clips):
    """LeakyReLU slope 1 makes the decoder affine; the authors' canvas adds only the (linear) root integration."""
    torch.manual_seed(0)
    model = RetargetNet(NetworkConfig(negative_slope=1.0)).eval()
    linear = Retargeter(model, retargeter.stats, PreprocessConfig(), torch.device("cpu"))
    poses = interpolate_grid(linear, *clips, vary=("motion", "view"), steps=5, canvas="authors").poses
    scale = np.abs(poses).max()
    w = blend_weights(5).double().numpy()
    for i in range(5):
        along_rows = (1 - w[i]) * poses[0, 0] + w[i] * poses[-1, 0]
        np.testing.assert_allclose(poses[i, 0], along_rows, atol=1e-5 * scale)
        for j in range(5):
            np.testing.assert_allclose(poses[i, j], poses[i, 0] + poses[0, j] - poses[0, 0], atol=1e-5 * scale)


def test_bad_settings_are_input_errors(retargeter, clips):
    for text in ("motion", "motion,motion", "motion,colour", "motion,view,body"):
        with pytest.raises(InputError, match="--vary"):
            parse_vary(text)
    assert parse_vary(" View , body ") == ("view", "body")
    with pytest.raises(InputError, match="canvas"):
        interpolate_grid(retargeter, *clips, canvas="paper")
    with pytest.raises(InputError, match="steps"):
        interpolate_grid(retargeter, *clips, steps=1)
    with pytest.raises(InputError, match="at least"):
        interpolate_grid(retargeter, *clips, frames=8)
    skeleton_only = Retargeter(RetargetNet(variant_config("skeleton")).eval(), retargeter.stats, PreprocessConfig(),
                               torch.device("cpu"))
    with pytest.raises(InputError, match="full network"):
        interpolate_grid(skeleton_only, *clips)


def test_grid_frames_draw_every_cell(retargeter, clips):
    grid = interpolate_grid(retargeter, *clips, steps=3, frames=16)
    frames = list(grid_frames(grid, cell=64))
    assert len(frames) == 16
    height, width = frames[0].shape[:2]
    assert frames[0].dtype == np.uint8 and (width - 3 * 64, height - 3 * 64) == (56, 48)
    for i in range(3):
        for j in range(3):
            cell = frames[5][48 + i * 64 + 2 : 48 + (i + 1) * 64 - 2, 56 + j * 64 + 2 : 56 + (j + 1) * 64 - 2]
            assert (cell.max(axis=-1) > 100).sum() > 20  # a figure in every cell


def test_command_writes_poses_and_a_video(people, tmp_path):
    a = write_track(people["tall"], tmp_path / "tall")
    b = write_track(people["small"], tmp_path / "small")
    runner = CliRunner()
    base = ["retarget", "interpolate", str(a), str(b), "--steps", "3", "--device", "cpu"]
    result = runner.invoke(app, [*base, "--vary", "body,view", "--out", str(tmp_path / "grid.npz")])
    assert result.exit_code == 0, result.output
    data = np.load(tmp_path / "grid.npz")
    assert data["poses"].shape == (3, 3, FRAMES + 8, 15, 2) and str(data["kept"]) == "motion"
    result = runner.invoke(app, [*base, "--frames", "16", "--cell", "48", "--out", str(tmp_path / "grid.mp4")])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "grid.mp4").stat().st_size > 0
    result = runner.invoke(app, [*base, "--vary", "motion,size", "--out", str(tmp_path / "x.npz")])
    assert result.exit_code == 2 and result.output.count("\n") == 1 and "--vary" in result.output
    result = runner.invoke(app, [*base, "--out", str(tmp_path / "grid.gif")])
    assert result.exit_code == 2 and ".mp4" in result.output
    result = runner.invoke(app, [*base, "--out", str(tmp_path / "grid.npz")])
    assert result.exit_code == 2 and "already exists" in result.output


# ---------------------------------------------------------------------------------------------------------
# Parity with the authors' interpolate.py (ChrisWu1997/2D-Motion-Retargeting), recomputed here from their
# documented procedure with our network's encoders and decoder: the first 120 OpenPose files of each clip,
# people[0], zero coordinates filled forward then backward, Gaussian sigma 2 over time, x 512 / 720; the
# input rows normalised with their meanpose_with_view / stdpose_with_view; codes from one pass over the clip;
# ``(1 - alpha) * c1 + alpha * c2`` with ``alpha = linspace(0, 1, n)``; decoded, de-normalised, MidHip
# re-inserted, root = cumulative velocity + (256, 256), no smoothing. Their --keep_attr names the attribute
# kept; in their matrix form cell (i, j) blends the first of the other two (in the order motion, body, view)
# with alpha_i and the second with alpha_j, which is our --vary with the same two names.

AUTHORS_KEEP = {("motion", "view"): "body", ("motion", "body"): "view", ("body", "view"): "motion"}
MAX_LENGTH = 120


def _authors_clip(folder, scale: float) -> np.ndarray:
    """[15, 2, T] joints of their ``openpose2motion``."""
    from scipy.ndimage import gaussian_filter1d

    motion = []
    for path in sorted(folder.iterdir())[:MAX_LENGTH]:
        joint = np.array(json.loads(path.read_text())["people"][0]["pose_keypoints_2d"]).reshape(-1, 3)[:15, :2]
        if motion:
            joint[joint == 0] = motion[-1][joint == 0]
        motion.append(joint)
    for i in range(len(motion) - 1, 0, -1):
        motion[i - 1][motion[i - 1] == 0] = motion[i][motion[i - 1] == 0]
    return gaussian_filter1d(np.stack(motion, axis=2), sigma=2, axis=-1) * scale


def _authors_input(clip: np.ndarray, mean: np.ndarray, std: np.ndarray) -> torch.Tensor:
    """[15, 2, T] -> [1, 30, T]: joints minus MidHip (MidHip row dropped), MidHip velocity last, normalised."""
    centre = clip[8]
    local = clip - centre
    velocity = np.concatenate([np.zeros((2, 1)), centre[:, 1:] - centre[:, :-1]], axis=1)[None]
    rows = np.concatenate([local[:8], local[9:], velocity])  # [15, 2, T]
    rows = (rows - mean[:, :, None]) / std[:, :, None]
    return torch.tensor(rows.reshape(30, -1), dtype=torch.float32)[None]


def _authors_output(y: torch.Tensor, mean: np.ndarray, std: np.ndarray) -> np.ndarray:
    """[1, 30, T] -> [T, 15, 2] in their 512 canvas, root from (256, 256)."""
    rows = y[0].numpy().reshape(15, 2, -1) * std[:, :, None] + mean[:, :, None]
    joints = np.concatenate([rows[:8], np.zeros((1, 2, rows.shape[-1])), rows[8:-1]])
    root = np.cumsum(rows[-1], axis=1) + np.array([[256.0], [256.0]])
    return (joints + root[None]).transpose(2, 0, 1)


@pytest.fixture(scope="module")
def authors(shared_dir):
    weights = shared_dir / "official_2dmr" / "weights"
    return {
        "weights": weights / "pretrained_full.pth",
        "retargeter": load_retargeter(weights / "pretrained_full.pth"),
        "mean": np.load(weights / "meanpose_with_view.npy"),
        "std": np.load(weights / "stdpose_with_view.npy"),
        "examples": shared_dir / "openpose_examples",
        "parity": shared_dir / "official_2dmr" / "parity",
    }


@torch.inference_mode()
def _authors_grid(authors, keep: str, steps: int) -> np.ndarray:
    net = authors["retargeter"].model
    inputs = [
        _authors_input(_authors_clip(authors["examples"] / clip, 512 / 720), authors["mean"], authors["std"])
        for clip in ("tall_man", "small_man")
    ]
    codes = [{"motion": net.encode_motion(x), "body": net.encode_body(x), "view": net.encode_view(x)} for x in inputs]
    first, second = (name for name in ("motion", "body", "view") if name != keep)
    alphas = torch.linspace(0, 1, steps)
    out = np.empty((steps, steps, MAX_LENGTH, 15, 2))
    for i in range(steps):
        for j in range(steps):
            cell = {keep: codes[0][keep]}
            for name, alpha in ((first, alphas[i]), (second, alphas[j])):
                cell[name] = (1 - alpha) * codes[0][name] + alpha * codes[1][name]
            out[i, j] = _authors_output(net.decode(cell["motion"], cell["body"], cell["view"]), authors["mean"],
                                        authors["std"])
    return out


@pytest.mark.parametrize("vary", list(AUTHORS_KEEP))
def test_authors_canvas_reproduces_their_interpolation(authors, vary, tmp_path):
    out = tmp_path / "grid.npz"
    result = CliRunner().invoke(app, [
        "retarget", "interpolate", str(authors["examples"] / "tall_man"), str(authors["examples"] / "small_man"),
        "--vary", ",".join(vary), "--canvas", "authors", "--weights", str(authors["weights"]), "--size", "720x720",
        "--steps", "5", "--out", str(out), "--device", "cpu",
    ])
    assert result.exit_code == 0, result.output
    ours = np.load(out)["poses"]
    theirs = _authors_grid(authors, AUTHORS_KEEP[vary], 5)
    assert ours.shape == theirs.shape == (5, 5, MAX_LENGTH, 15, 2)
    assert np.abs(ours - theirs).max() < 1e-3
    # Cell (0, 0) is tall_man's own reconstruction, which the authors' code wrote out itself.
    recon = np.load(authors["parity"] / "full_self_recon_tall_man.npy").transpose(2, 0, 1)  # [120, 15, 2]
    assert np.abs(ours[0, 0] - recon).max() < 1e-3


def test_a_clip_at_another_rate_runs_at_the_networks_and_comes_back_at_its_own(retargeter, clips):
    a, b = (resample(c.frames(0, FRAMES), 60.0) for c in clips)  # 60 fps: every other frame is a 30 fps one
    grid = interpolate_grid(retargeter, a, b, vary=("motion", "view"), steps=2)
    assert grid.poses.shape[2] == len(a) and grid.fps == 60.0
    at_30 = interpolate_grid(retargeter, *(c.frames(0, FRAMES) for c in clips), vary=("motion", "view"), steps=2)
    # the same network input on even frames; the body's scale and place are medians over all of A's own frames
    np.testing.assert_allclose(grid.poses[:, :, ::2], at_30.poses, atol=0.5)
    # a corner is still plain retargeting (which runs at the network's rate too)
    expected = retargeter.retarget(a, retargeter.reference_codes(a)).joints
    np.testing.assert_allclose(grid.poses[0, 0], expected, atol=2e-3)
