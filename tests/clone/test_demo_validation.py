"""The cloning-kind measure: the demo's pairs built from a split's clips, scored as the demo scores."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
import torch
from typer.testing import CliRunner

from clone.cli.main import app
from clone.demo import validation
from clone.demo.config import PAIRS
from clone.demo.scenes import edge_distance
from pose_io.errors import InputError
from pose_io.measures import reference_limb_lengths
from retarget.api import PACKAGED_WEIGHTS
from retarget.network.checkpoint import save_checkpoint
from retarget.network.model import RetargetNet, variant_config
from retarget.network.preprocess import NormStats
from retarget.world import MotionWorld
from tests.retarget.evaluate.helpers import TINY

FRAMES = 48


@pytest.fixture(scope="module")
def tiny_mocap(shared_dir: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("mocap")
    for rel in TINY:  # val: two takes of one walk
        shutil.copy(shared_dir / "mocap" / rel, root / Path(rel).name)
    return root


@pytest.fixture(scope="module")
def cache(tiny_mocap: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("cache")
    MotionWorld.build(tiny_mocap, folder)
    return folder


@pytest.fixture(scope="module")
def world(tiny_mocap: Path, cache: Path) -> MotionWorld:
    return MotionWorld.build(tiny_mocap, cache)


@pytest.fixture(scope="module")
def cases(world: MotionWorld, tiny_mocap: Path) -> list[validation.CloningCase]:
    return validation.cloning_cases(world.split("val").clips, tiny_mocap, FRAMES)


def test_every_clip_gives_the_demos_three_pairs(world, tiny_mocap, cases) -> None:
    clips = world.split("val").clips
    used = list(dict.fromkeys(c.clip for c in cases))
    assert used and set(used) <= {c["path"] for c in clips}
    assert [c.kind for c in cases] == [p.name for p in PAIRS] * len(used)  # in the split's order, pair by pair
    margin = validation.DEMO.edge_margin * validation.DEMO.render_size
    for case in cases:
        assert len(case.driver) == len(case.truth) == FRAMES
        assert case.driver.layout == case.truth.layout == "body15"
        assert edge_distance(case.truth) >= margin
        # The truth is the reference's body: the view driver has it, the child drivers are smaller.
        truth_limbs = reference_limb_lengths(case.truth.joints)
        driver_limbs = reference_limb_lengths(case.driver.joints)
        if case.kind == "view":
            assert np.nanmedian(driver_limbs / truth_limbs) == pytest.approx(1.0, abs=0.15)
        else:
            assert np.nanmedian(driver_limbs / truth_limbs) < 0.75
    assert len(validation.cloning_cases(world.split("val").clips, tiny_mocap, FRAMES, limit=1)) == len(PAIRS)
    with pytest.raises(InputError, match="no clip of at least"):
        validation.cloning_cases(world.split("val").clips, tiny_mocap, 100_000)


def test_a_turning_driver_per_clip_turns_with_its_truth_and_stays_apart_from_all(world, tiny_mocap, cases) -> None:
    from clone.synth import get_character
    from clone.synth.performance import render_performance
    from retarget.world import load_motion
    from retarget.world.turns import Turn

    turned = validation.cloning_cases(world.split("val").clips, tiny_mocap, FRAMES, turns=True)
    plain = [c for c in turned if c.kind != validation.TURN_KIND]
    assert [(c.clip, c.kind) for c in plain] == [(c.clip, c.kind) for c in cases]  # the demo's pairs unchanged
    assert all(a.driver.equals(b.driver) and a.truth.equals(b.truth) for a, b in zip(plain, cases, strict=True))
    turning = [c for c in turned if c.kind == validation.TURN_KIND]
    assert turning and len({c.clip for c in turning}) == len(turning)  # one per clip
    same_clip = next(c for c in cases if c.clip == turning[0].clip and c.kind == "both")  # its body and camera
    assert np.abs(turning[0].truth.joints - same_clip.truth.joints).max() > 5  # pixels: the truth turned too

    errors = validation.score(turned, {"ours": lambda c: c.driver, "other": lambda c: c.driver})  # as it is
    doc = validation.summarise(turned, errors, "ours")
    pose = doc["measures"]["pose_rmse_pct"]["ours"]
    assert doc["kinds"] == [p.name for p in PAIRS] + [validation.TURN_KIND]
    is_turn = np.array([c.kind == validation.TURN_KIND for c in turned])
    assert pose["all"]["mean"] == pytest.approx(errors["pose_rmse_pct"]["ours"][~is_turn].mean())
    assert pose["turn"]["mean"] == pytest.approx(errors["pose_rmse_pct"]["ours"][is_turn].mean())

    # A half turn over the case: the body ends with its back to the camera (its shoulders change sides).
    clip = world.split("val").clips[0]
    motion = load_motion(tiny_mocap / clip["path"], fps=world.config.fps)
    skeleton, look, _ = get_character("child")
    window = {"size": 256, "start": validation.CASE_START, "frames": FRAMES}
    half = render_performance(motion, skeleton, look, yaw=0.0, turn=Turn(180.0, 0.0, FRAMES - 1), **window)[1]
    still = render_performance(motion, skeleton, look, yaw=0.0, **window)[1]
    right, left = half.joint_layout.index("r_shoulder"), half.joint_layout.index("l_shoulder")

    def side(track, t):
        return np.sign(track.joints[t, right, 0] - track.joints[t, left, 0])

    assert side(half, 0) == side(still, 0) == side(still, FRAMES - 1) != side(half, FRAMES - 1)


def test_a_travelling_driver_walks_across_a_wide_picture_and_keeps_its_travel(world, tiny_mocap, cases) -> None:
    clips = world.split("val").clips  # two takes of one walk: at 64 frames both leave the square frame
    walked = validation.cloning_cases(clips, tiny_mocap, 64, travelling=True)
    assert [c.kind for c in walked] == [validation.TRAVEL_KIND] * 2 and len({c.clip for c in walked}) == 2
    margin = validation.DEMO.edge_margin * validation.DEMO.render_size
    for case in walked:
        assert case.picture == validation.WIDE and case.driver.image_size == case.truth.image_size == (768, 256)
        assert validation.travel(case.truth) >= validation.TRAVEL_LEAST and edge_distance(case.truth) >= margin
    with_travel = validation.cloning_cases(clips, tiny_mocap, FRAMES, travelling=True)
    plain = [c for c in with_travel if c.kind != validation.TRAVEL_KIND]
    assert [(c.clip, c.kind) for c in plain] == [(c.clip, c.kind) for c in cases]  # the demo's pairs unchanged
    assert all(a.truth.equals(b.truth) for a, b in zip(plain, cases, strict=True))

    references = validation.references()
    assert references[validation.WIDE].image_size == (768, 256)
    height = {p: np.ptp(r.to_layout("body15").joints[0, :, 1]) for p, r in references.items()}
    assert height[validation.WIDE] == pytest.approx(height[validation.SQUARE], rel=0.02)  # the same body, wider
    methods = {"ours": validation.network_drive(None, references),
               "global scaling (EDN)": validation.global_scale_drive(references)}
    driven = methods["ours"](walked[0])
    assert driven.image_size == (768, 256) and validation.travel(driven) > 0.5 * validation.travel(walked[0].truth)
    errors = validation.score(walked, methods)
    doc = validation.summarise(walked, errors, "ours")
    placement = doc["measures"]["root_rmse_pct"]
    assert doc["kinds"] == [validation.TRAVEL_KIND] and np.isnan(placement["ours"]["all"]["mean"])  # not the demo's
    # The travel kept on the stage: placement no worse than global scaling's (the travel issue's goal).
    assert placement["ours"]["travel"]["mean"] < placement["global scaling (EDN)"]["travel"]["mean"]


def test_scores_rank_the_shipped_network_over_global_scaling_and_an_untrained_one(cases, tmp_path) -> None:
    torch.manual_seed(0)
    untrained = save_checkpoint(tmp_path / "untrained.pt", RetargetNet(variant_config("full")),
                                NormStats(np.zeros((15, 2)), np.full((15, 2), 50.0)))  # fmt: skip
    references = validation.references()
    methods = {
        "ours": validation.network_drive(None, references),
        "same": validation.network_drive(PACKAGED_WEIGHTS, references),
        "untrained": validation.network_drive(untrained, references),
        "global scaling (EDN)": validation.global_scale_drive(references),
    }
    errors = validation.score(cases, methods)
    doc = validation.summarise(cases, errors, "ours")
    assert list(doc["measures"]) == list(validation.MEASURES) == ["pose_rmse_pct", "root_rmse_pct"]
    assert doc["cases"] == len(cases) and doc["kinds"] == [p.name for p in PAIRS]
    for key, rows in doc["measures"].items():
        assert rows["same"]["vs_ours"]["all"] == {"mean": 0.0, "se": 0.0}  # the same weights, the same errors
        assert rows["ours"]["all"]["mean"] == pytest.approx(errors[key]["ours"].mean())
        diff = rows["untrained"]["vs_ours"]["all"]
        assert diff["mean"] == pytest.approx((errors[key]["untrained"] - errors[key]["ours"]).mean())
    pose = doc["measures"]["pose_rmse_pct"]
    assert pose["ours"]["all"]["mean"] < pose["untrained"]["all"]["mean"]
    for kind in ("proportions", "both"):  # the paper's claim on the demo's pairs
        assert pose["ours"][kind]["mean"] < pose["global scaling (EDN)"][kind]["mean"]
    # The errors are the demo's: clone.metrics.evaluate_track of the same driven track.
    from clone.metrics import evaluate_track
    from pose_io.measures import reference_limb_lengths, skeleton_height

    driven = methods["ours"](cases[0])
    ref15 = references[validation.SQUARE].to_layout("body15")
    full = evaluate_track(driven, reference_limb_lengths(ref15.joints), skeleton_height(ref15.joints, "body15"),
                          cases[0].truth).summary  # fmt: skip
    assert errors["pose_rmse_pct"]["ours"][0] == pytest.approx(full["pose_rmse_pct"])
    assert errors["root_rmse_pct"]["ours"][0] == pytest.approx(full["root_rmse_pct"])


def test_command_writes_the_tables_and_refuses_bad_input(tiny_mocap, cache, tmp_path) -> None:
    runner = CliRunner()
    out = tmp_path / "cloning"
    args = ["retarget", "eval-cloning", "--mocap", str(tiny_mocap), "--cache", str(cache), "--out",
            str(out), "--frames", str(FRAMES), "--clips", "1", "--compare", f"again={PACKAGED_WEIGHTS}",
            "--threads", "1", "--device", "cpu"]  # fmt: skip
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    doc = json.loads((out / "cloning.json").read_text())
    assert list(doc["measures"]["pose_rmse_pct"]) == ["ours", "again", "global scaling (EDN)"]
    assert doc["cases"] == len(doc["case_list"]) == len(PAIRS) + 1  # the demo's pairs and the turning driver
    assert doc["kinds"][-1] == "turn" and "turn: child at -30° turning" in doc["pairs"]
    assert doc["measures"]["root_rmse_pct"]["again"]["vs_ours"]["all"]["mean"] == 0.0
    table = (out / "cloning.md").read_text()
    assert "## Pose error" in table and "## Placement" in table and table.count("Paired difference to ours") == 2
    again = runner.invoke(app, args)  # --out exists
    assert again.exit_code == 2 and again.output.count("error:") == 1
    clash = runner.invoke(app, [*args[:-6], "--compare", f"ours={PACKAGED_WEIGHTS}", "--overwrite"])
    assert clash.exit_code == 2 and "row name is taken" in clash.output
    assert json.loads((out / "cloning.json").read_text()) == doc  # nothing the user had is touched
