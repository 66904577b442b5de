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
from clone.demo.scenes import edge_distance, reference_track
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


def test_scores_rank_the_shipped_network_over_global_scaling_and_an_untrained_one(cases, tmp_path) -> None:
    torch.manual_seed(0)
    untrained = save_checkpoint(tmp_path / "untrained.pt", RetargetNet(variant_config("full")),
                                NormStats(np.zeros((15, 2)), np.full((15, 2), 50.0)))  # fmt: skip
    reference = reference_track(validation.DEMO)
    methods = {
        "ours": validation.network_drive(None, reference),
        "same": validation.network_drive(PACKAGED_WEIGHTS, reference),
        "untrained": validation.network_drive(untrained, reference),
        "global scaling (EDN)": validation.global_scale_drive(reference),
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

    driven = methods["ours"](cases[0].driver)
    ref15 = reference.to_layout("body15")
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
    assert doc["cases"] == len(PAIRS) and len(doc["case_list"]) == len(PAIRS)
    assert doc["measures"]["root_rmse_pct"]["again"]["vs_ours"]["all"]["mean"] == 0.0
    table = (out / "cloning.md").read_text()
    assert "## Pose error" in table and "## Placement" in table and table.count("Paired difference to ours") == 2
    again = runner.invoke(app, args)  # --out exists
    assert again.exit_code == 2 and again.output.count("error:") == 1
    clash = runner.invoke(app, [*args[:-6], "--compare", f"ours={PACKAGED_WEIGHTS}", "--overwrite"])
    assert clash.exit_code == 2 and "row name is taken" in clash.output
    assert json.loads((out / "cloning.json").read_text()) == doc  # nothing the user had is touched
