"""Evaluation: metrics on known inputs, silhouettes, 3D references, case sampling and `clone retarget eval`."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
import torch
from typer.testing import CliRunner

from clone.cli.main import app
from pose_io.errors import InputError
from retarget.checkpoint import save_checkpoint
from retarget.evaluate import (
    BASELINES,
    OFFICIAL_FILES,
    REFERENCES_3D,
    ClipMotions,
    EvalConfig,
    case_scores,
    global_scale_3d,
    naive_copy_3d,
    offset_aligned,
    pca_2d,
    pose_errors,
    root_aligned,
    rotation_copy_3d,
    sample_cases,
    silhouette,
)
from retarget.model import RetargetNet, variant_config
from retarget.preprocess import ROOT_INDEX, NormStats
from retarget.world import MotionWorld, load_motion

TINY = (
    "bandai_namco/dataset-1/dataset-1_walk_normal_001.bvh.gz",
    "bandai_namco/dataset-1/dataset-1_bow_normal_001.bvh.gz",
    "bandai_namco/dataset-2/dataset-2_walk_normal_001.bvh.gz",
    "bandai_namco/dataset-2/dataset-2_walk_normal_002.bvh.gz",
)


@pytest.fixture(scope="module")
def tiny_mocap(shared_dir: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Four clips in one folder: the world puts one motion group in each split (val: two takes of one walk)."""
    root = tmp_path_factory.mktemp("mocap")
    for rel in TINY:
        shutil.copy(shared_dir / "mocap" / rel, root / Path(rel).name)
    return root


@pytest.fixture(scope="module")
def cache(tiny_mocap: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("cache")
    MotionWorld.build(tiny_mocap, folder)  # the defaults `clone retarget eval` uses
    return folder


@pytest.fixture(scope="module")
def tiny_weights(tmp_path_factory: pytest.TempPathFactory) -> Path:
    torch.manual_seed(0)
    path = tmp_path_factory.mktemp("weights") / "tiny.pt"
    stats = NormStats(np.zeros((15, 2)), np.full((15, 2), 50.0))
    return save_checkpoint(path, RetargetNet(variant_config("full")), stats)


# -- metrics ----------------------------------------------------------------------------------------------


def test_identical_poses_score_perfectly() -> None:
    joints = np.random.default_rng(0).uniform(0, 100, (10, 15, 2))
    assert pose_errors(joints, joints, 100.0) == {"mse_x1e3": 0.0, "rmse_pct": 0.0, "pck_0.05": 1.0, "pck_0.1": 1.0,
                                                   "amplitude": 1.0}
    for scores in case_scores(joints, joints, 100.0).values():
        assert scores["mse_x1e3"] == 0.0 and scores["pck_0.05"] == 1.0


def test_known_displacements_give_known_errors() -> None:
    truth = np.zeros((4, 10, 2))
    pred = truth.copy()
    pred[:, :5] += [3.0, 4.0]  # half the joints 5 px away (5 % of a 100 px height)...
    pred[:, 5:] += [0.0, 12.0]  # ...the other half 12 px (12 %)
    scores = pose_errors(pred, truth, height=100.0)
    assert scores["mse_x1e3"] == pytest.approx((0.03**2 + 0.04**2 + 0.12**2) / 4 * 1e3)
    assert scores["rmse_pct"] == pytest.approx(np.sqrt((5.0**2 + 12.0**2) / 2))
    assert scores["pck_0.05"] == 0.0  # 5 % is not within 5 %
    assert scores["pck_0.1"] == 0.5
    # The same displacement in a twice as tall target is half as large.
    assert pose_errors(pred, truth, height=200.0)["rmse_pct"] == pytest.approx(scores["rmse_pct"] / 2)


def test_alignments_separate_placement_from_pose() -> None:
    rng = np.random.default_rng(1)
    truth = rng.uniform(100, 400, (8, 15, 2))
    moved = truth + [30.0, -20.0]  # the right motion in the wrong place
    scores = case_scores(moved, truth, 300.0)
    assert scores["pose"]["mse_x1e3"] == pytest.approx(0.0, abs=1e-12)
    assert scores["with_root"]["mse_x1e3"] == pytest.approx(0.0, abs=1e-12)
    assert scores["placed"]["rmse_pct"] == pytest.approx(100 * np.hypot(30, 20) / 300)
    # A pose scaled by 1.1 about MidHip: every root-relative joint is 10 % of its distance off.
    root = truth[:, ROOT_INDEX : ROOT_INDEX + 1]
    scaled = root + 1.1 * (truth - root)
    local = np.delete(truth - root, ROOT_INDEX, axis=1)
    expected = 100 * np.sqrt(np.mean(np.sum((0.1 * local / 300.0) ** 2, axis=-1)))
    assert case_scores(scaled, truth, 300.0)["pose"]["rmse_pct"] == pytest.approx(expected)
    assert root_aligned(truth).shape == (8, 14, 2)
    assert np.allclose(offset_aligned(moved, truth), truth)


def test_silhouette_known_value_separated_and_random() -> None:
    # 1-D points: cluster 0 = {0, 1}, cluster 1 = {10}. s(0) = (10 - 1) / 10, s(1) = (9 - 1) / 9, s(10) = 0.
    assert silhouette(np.array([[0.0], [1.0], [10.0]]), np.array([0, 0, 1])) == pytest.approx((0.9 + 8 / 9) / 3)
    rng = np.random.default_rng(0)
    labels = np.repeat(np.arange(3), 20)
    centres = np.array([[0.0, 0.0], [100.0, 0.0], [0.0, 100.0]])
    assert silhouette(centres[labels] + rng.normal(0, 1, (60, 2)), labels) > 0.95
    assert abs(silhouette(rng.normal(0, 1, (300, 8)), rng.integers(0, 3, 300))) < 0.05
    with pytest.raises(ValueError):
        silhouette(np.zeros((4, 2)), np.zeros(4))


def test_pca_finds_the_spread_directions() -> None:
    rng = np.random.default_rng(0)
    x = rng.normal(0, 0.01, (50, 6))
    x[:, 3] += np.linspace(-5, 5, 50)  # the largest spread
    x[:, 1] += rng.choice([-1.0, 1.0], 50)  # the second
    xy = pca_2d(x)
    assert abs(np.corrcoef(xy[:, 0], x[:, 3])[0, 1]) > 0.99
    assert abs(np.corrcoef(xy[:, 1], x[:, 1])[0, 1]) > 0.99


# -- world cases and 3D references ------------------------------------------------------------------------


def test_3d_references_against_the_world_truth(cache: Path, tiny_mocap: Path) -> None:
    split = MotionWorld.build(tiny_mocap, cache).split("test")
    a, b = 0, split.num_characters - 1
    skel_a, skel_b = split.characters[a], split.characters[b]
    pos_a = split.window3d(0, a)
    truth = split.window(0, b, 4)
    height = skel_b.height * split.camera(4).scale
    seen = {f.__name__: split.project(f(pos_a, skel_a, skel_b)[None], [4])[0]
            for f in (naive_copy_3d, global_scale_3d, rotation_copy_3d)}  # fmt: skip
    # Rotations copied onto B's bones are the truth's pose exactly; only the root path differs.
    assert case_scores(seen["rotation_copy_3d"], truth, height)["pose"]["rmse_pct"] < 1e-3
    assert case_scores(seen["naive_copy_3d"], truth, height)["pose"]["rmse_pct"] > 1.0
    # Onto A's own skeleton every reference is the identity.
    for f in (naive_copy_3d, global_scale_3d, rotation_copy_3d):
        assert np.allclose(f(pos_a, skel_a, skel_a), pos_a, atol=1e-5)
    assert set(REFERENCES_3D) == {"3D naive copy", "3D global scale", "3D rotation copy"}


def test_cases_are_seeded_and_references_share_no_frame(cache: Path, tiny_mocap: Path) -> None:
    split = MotionWorld.build(tiny_mocap, cache).split("test")  # one clip of 138 frames: windows overlap
    config = EvalConfig(pairs=40)
    cases = sample_cases(split, split, config, np.random.default_rng(3))
    assert cases == sample_cases(split, split, config, np.random.default_rng(3))
    for case in cases:
        assert case.source_character != case.character
        drv, ref = split.window_labels[case.motion], split.window_labels[case.reference]
        assert drv.start + 64 <= ref.start or ref.start + 64 <= drv.start
        assert abs(case.pitch) <= config.max_pitch
    with pytest.raises(InputError, match="shares none"):
        sample_cases(split, split, EvalConfig(pairs=1, length=128), np.random.default_rng(0))


def test_extra_clips_replay_like_the_world(cache: Path, tiny_mocap: Path) -> None:
    split = MotionWorld.build(tiny_mocap, cache).split("test")
    motion = load_motion(tiny_mocap / Path(TINY[1]).name)  # the test split's own clip
    clips = ClipMotions([motion], split.characters, 64, 32)
    assert [lab.start for lab in clips.window_labels] == [lab.start for lab in split.window_labels]
    for m in range(clips.num_motions):
        assert np.allclose(clips.window3d(m, 2), split.window3d(m, 2), atol=1e-5)
    with pytest.raises(InputError, match="shorter"):
        ClipMotions([motion], split.characters, 512, 32)


# -- the command ------------------------------------------------------------------------------------------


def test_cli_writes_the_table_plots_and_json(
    shared_dir: Path, tiny_mocap: Path, cache: Path, tiny_weights: Path, tmp_path: Path
) -> None:
    out = tmp_path / "eval"
    args = ["retarget", "eval", "--mocap", str(tiny_mocap), "--cache", str(cache), "--weights", str(tiny_weights),
            "--compare", f"no triplet={tiny_weights}", "--bvh", str(tiny_mocap / Path(TINY[0]).name),
            "--official", str(shared_dir / "official_2dmr" / "weights"),
            "--pairs", "3", "--split", "val", "--threads", "1", "--device", "cpu", "--out", str(out)]  # fmt: skip
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    doc = json.loads((out / "eval.json").read_text())
    rows = {"ours", "no triplet", *OFFICIAL_FILES, *BASELINES, *REFERENCES_3D}
    assert list(doc["results"]) == ["val split", "extra mocap (1 clip)"]
    for source in doc["results"].values():
        assert set(source) == rows
        for row in source.values():
            assert set(row) == {"pose", "with_root", "placed"}
            assert all(np.isfinite(v) for v in row["pose"].values())
            assert 0.0 <= row["placed"]["pck_0.1"] <= 1.0
    assert set(doc["silhouettes"]["ours"]) == {"motion", "body", "view"}
    assert all(-1.0 <= v <= 1.0 for v in doc["silhouettes"]["no triplet"].values())
    assert set(doc["silhouettes"]["authors' view-only"]) == {"motion", "view"}
    assert sorted(p.name for p in out.glob("*.png")) == [
        "codes_authors_full.png", "codes_authors_skeleton_only.png", "codes_authors_view_only.png",
        "codes_no_triplet.png", "codes_ours.png",
    ]
    table = (out / "eval.md").read_text()
    assert "| ours |" in table and "| 3D rotation copy |" in table and "h² × 10⁻³" in table
    assert "| ours |" in result.output  # printed too
    again = CliRunner().invoke(app, args)
    assert again.exit_code == 2 and "already exists" in again.output


def test_cli_input_errors_are_one_line(tiny_mocap: Path, cache: Path, tiny_weights: Path, tmp_path: Path) -> None:
    base = ["retarget", "eval", "--mocap", str(tiny_mocap), "--cache", str(cache), "--weights", str(tiny_weights),
            "--pairs", "2", "--split", "val"]  # fmt: skip
    cases = {
        "expected NAME=PATH": ["--compare", "nopath"],
        "none of pretrained_full.pth": ["--official", str(tmp_path)],
        "that row name is taken": ["--compare", f"ours={tiny_weights}"],
        "valid: test, val": ["--split", "train"],
    }
    for k, (message, extra) in enumerate(cases.items()):
        out = tmp_path / f"out{k}"
        result = CliRunner().invoke(app, [*base, *extra, "--out", str(out)])
        assert result.exit_code == 2, result.output
        assert message in result.output and "Traceback" not in result.output
        assert not out.exists()
