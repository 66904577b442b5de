"""Mapping mocap rigs onto the canonical skeleton: name tables, units, up axis, sides, head points."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from pose_io.errors import InputError
from retarget.world import WORLD_JOINTS, load_motion, skeleton_of
from retarget.world.camera import facing_vectors
from retarget.world.rigs import rig_naming
from tests.retarget.world.humanoid import BANDAI_NAMCO, MAX3DS, MOTIONBUILDER, ROLES, humanoid_bvh

J = WORLD_JOINTS.index

# One file per shared folder (and the AMC reader), with the naming each must be recognised as.
SHARED_FILES = [
    ("bandai_namco/dataset-1/dataset-1_walk_normal_001.bvh.gz", "bandai_namco"),
    ("cmu_iclone/subjects/007/007_01.bvh.gz", "character_creator"),
    ("cmu_iclone/subjects/002/002_01.bvh.gz", "character_creator"),  # RL_BoneRoot, Z-up root variant
    ("cmu_fairmotion/01_01.bvh.gz", "cmu_motionbuilder"),
    ("cmu_fairmotion/01_01.amc", "acclaim"),
]


@pytest.mark.parametrize(("rel", "naming"), SHARED_FILES)
def test_every_shared_rig_maps_to_a_human(shared_dir: Path, rel: str, naming: str) -> None:
    path = shared_dir / "mocap" / rel
    assert rig_naming(path) == naming
    motion = load_motion(path, fps=30.0)
    pos = motion.positions
    assert pos.shape[1:] == (18, 3) and pos.dtype == np.float32 and motion.fps == 30.0
    skel = skeleton_of(motion)
    assert 1.45 < skel.height < 1.95, skel.height
    # Y up, on the ground, first root over the origin.
    assert (pos[:, J("head"), 1] > pos[:, J("mid_hip"), 1]).mean() > 0.95
    assert (pos[:, J("mid_hip"), 1] > pos[:, J("l_ankle"), 1]).mean() > 0.95
    feet = pos[:, [J("l_ankle"), J("r_ankle"), J("l_big_toe"), J("r_big_toe")], 1].min(axis=1)
    assert np.percentile(feet, 2) == pytest.approx(0.0, abs=1e-4) and feet.min() > -0.05
    np.testing.assert_allclose(pos[0, J("mid_hip"), [0, 2]], 0.0, atol=1e-5)
    # OpenPose semantics for the derived joints.
    np.testing.assert_allclose(pos[:, J("mid_hip")], (pos[:, J("l_hip")] + pos[:, J("r_hip")]) / 2, atol=1e-5)
    np.testing.assert_allclose(pos[:, J("neck")], (pos[:, J("l_shoulder")] + pos[:, J("r_shoulder")]) / 2, atol=1e-5)
    # The skull centre is above the shoulders, the nose in front of it (toward the facing direction).
    assert (pos[:, J("head"), 1] > pos[:, J("neck"), 1] + 0.08).mean() > 0.9
    fwd = facing_vectors(pos)
    nose = pos[:, J("nose"), [0, 2]] - pos[:, J("head"), [0, 2]]
    assert (np.sum(nose * fwd, axis=1) > 0.03).mean() > 0.9
    # Sensible limbs: thigh and shin 0.3-0.6 m, forearm 0.15-0.35 m.
    for bone, lo, hi in (("l_knee", 0.3, 0.6), ("l_ankle", 0.3, 0.6), ("l_wrist", 0.15, 0.35)):
        assert lo < skel.length(bone) < hi, (bone, skel.length(bone))


@pytest.mark.parametrize(
    ("rel", "frames"),
    [
        ("bandai_namco/dataset-1/dataset-1_walk_normal_001.bvh.gz", None),
        ("cmu_iclone/subjects/007/007_01.bvh.gz", None),
        ("cmu_fairmotion/01_01.amc", 200),  # forward jumps, before turning around
        ("cmu_fairmotion/01_01.bvh.gz", 200),
    ],
)
def test_left_is_the_characters_own_left(shared_dir: Path, rel: str, frames: int | None) -> None:
    """In clips that move forward, forward (from left x up) points along the travel."""
    pos = load_motion(shared_dir / "mocap" / rel).positions[:frames]
    travel = pos[-1, J("mid_hip"), [0, 2]] - pos[0, J("mid_hip"), [0, 2]]
    assert np.linalg.norm(travel) > 1.0
    fwd = facing_vectors(pos).mean(axis=0)
    assert fwd @ travel / np.linalg.norm(travel) / np.linalg.norm(fwd) > 0.9


def test_resampling_keeps_duration(tmp_path: Path) -> None:
    path = tmp_path / "walk_120fps.bvh"
    path.write_text(humanoid_bvh(MOTIONBUILDER, frames=241, step=1.2, swing=25.0, period=120.0, frame_time=1 / 120))
    a = load_motion(path, fps=60.0)
    b = load_motion(path, fps=30.0)
    assert (a.num_frames, b.num_frames) == (121, 61)  # 2 s either way
    assert b.num_frames == (a.num_frames - 1) // 2 + 1
    # Same frames; only the ground level (a percentile over the frames kept) may move a little.
    diff = b.positions - a.positions[::2]
    np.testing.assert_allclose(diff[..., [0, 2]], 0.0, atol=1e-5)
    np.testing.assert_allclose(diff[..., 1], diff[0, 0, 1], atol=1e-5)
    assert abs(diff[0, 0, 1]) < 0.01


# ---------------------------------------------------------------------------------------------------
# Synthetic rigs: one humanoid written under several namings (tests/retarget/world/humanoid.py).


@pytest.mark.parametrize(
    ("names", "scale", "naming"),
    [
        ({k: "mixamorig:" + v for k, v in MOTIONBUILDER.items()}, 1.0, "mixamo"),
        (MOTIONBUILDER, 0.01, "rokoko"),  # metres
        (MAX3DS, 1.0, "cmu_3dsmax"),
        ({k: "CC_Base_" + v for k, v in {
            "hips": "Hip", "spine": "Spine01", "neck": "NeckTwist01", "head": "Head", "l_collar": "L_Clavicle",
            "l_shoulder": "L_Upperarm", "l_elbow": "L_Forearm", "l_wrist": "L_Hand", "l_hip": "L_Thigh",
            "l_knee": "L_Calf", "l_ankle": "L_Foot", "l_toe": "L_ToeBase", "r_collar": "R_Clavicle",
            "r_shoulder": "R_Upperarm", "r_elbow": "R_Forearm", "r_wrist": "R_Hand", "r_hip": "R_Thigh",
            "r_knee": "R_Calf", "r_ankle": "R_Foot", "r_toe": "R_ToeBase"}.items()}, 1.0, "character_creator"),
        ({k: "Bip01 " + v for k, v in {
            "hips": "Pelvis", "spine": "Spine", "neck": "Neck", "head": "Head", "l_collar": "L Clavicle",
            "l_shoulder": "L UpperArm", "l_elbow": "L Forearm", "l_wrist": "L Hand", "l_hip": "L Thigh",
            "l_knee": "L Calf", "l_ankle": "L Foot", "l_toe": "L Toe0", "r_collar": "R Clavicle",
            "r_shoulder": "R UpperArm", "r_elbow": "R Forearm", "r_wrist": "R Hand", "r_hip": "R Thigh",
            "r_knee": "R Calf", "r_ankle": "R Foot", "r_toe": "R Toe0"}.items()}, 1 / 2.54, "max_biped"),  # inches
        (BANDAI_NAMCO, 1.0, "bandai_namco"),
    ],
)
def test_namings_units_and_sides(tmp_path: Path, names: dict[str, str], scale: float, naming: str) -> None:
    path = tmp_path / "rig.bvh"
    path.write_text(humanoid_bvh(names, scale))
    assert rig_naming(path) == naming
    motion = load_motion(path)
    pos = motion.positions[0]
    # Metres whatever the file unit; joints where the rig puts them (hip joints 0.9 m up, 18 cm apart).
    assert pos[J("l_hip"), 0] - pos[J("r_hip"), 0] == pytest.approx(0.18, abs=1e-5)
    assert pos[J("l_knee"), 1] - pos[J("l_ankle"), 1] == pytest.approx(0.41, abs=1e-5)
    assert pos[J("l_shoulder"), 0] > pos[J("r_shoulder"), 0]
    assert pos[J("nose"), 2] > pos[J("head"), 2]  # facing +Z, the nose points forward
    assert 1.5 < skeleton_of(motion).height < 1.9


def test_z_up_rig_is_turned_y_up(tmp_path: Path) -> None:
    text = humanoid_bvh(MOTIONBUILDER)
    # Turn the whole rig Z up at the root: 90 degrees about X takes +Y to +Z.
    text = text.replace("CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation",
                        "CHANNELS 6 Xposition Yposition Zposition Xrotation Yrotation Zrotation")
    lines = text.splitlines()
    start = lines.index("MOTION") + 3
    for k in range(start, len(lines)):
        vals = lines[k].split()
        vals[3] = "90"
        lines[k] = " ".join(vals)
    path = tmp_path / "zup.bvh"
    path.write_text("\n".join(lines) + "\n")
    pos = load_motion(path).positions
    assert pos[0, J("head"), 1] > 1.4 and pos[0, J("l_ankle"), 1] < 0.1


def test_unknown_rig_lists_unmapped_world_joints(tmp_path: Path) -> None:
    names = dict(MOTIONBUILDER, l_toe="Pinky", r_toe="Thumb", head="Skull")
    path = tmp_path / "odd.bvh"
    path.write_text(humanoid_bvh(names))
    with pytest.raises(InputError) as info:
        load_motion(path)
    msg = str(info.value)
    assert "odd.bvh" in msg and "unknown rig" in msg
    assert "l_big_toe" in msg and "r_big_toe" in msg and "head" in msg and "nose" in msg
    assert "l_knee" not in msg


def test_user_json_mapping(tmp_path: Path) -> None:
    names = {role: f"bone_{k}" for k, role in enumerate(ROLES)}
    path = tmp_path / "custom.bvh"
    path.write_text(humanoid_bvh(names))
    keys = {"l_hip": "l_hip", "r_hip": "r_hip", "l_knee": "l_knee", "r_knee": "r_knee", "l_ankle": "l_ankle",
            "r_ankle": "r_ankle", "l_big_toe": "l_toe", "r_big_toe": "r_toe", "l_shoulder": "l_shoulder",
            "r_shoulder": "r_shoulder", "l_elbow": "l_elbow", "r_elbow": "r_elbow", "l_wrist": "l_wrist",
            "r_wrist": "r_wrist", "neck": "neck", "head": "head"}
    mapping = {key: names[role] for key, role in keys.items()}
    (tmp_path / "map.json").write_text(json.dumps({"joints": mapping}))
    motion = load_motion(path, mapping=tmp_path / "map.json")
    assert motion.positions[0, J("l_hip"), 0] > motion.positions[0, J("r_hip"), 0]
    # A nose joint may be given directly.
    with_nose = load_motion(path, mapping=dict(mapping, nose=names["head"]))
    # The rig's head joint is 10 cm above its neck joint, 1.54 m above the toes (the ground).
    np.testing.assert_allclose(with_nose.positions[0, J("nose")], [0.0, 1.54, 0.0], atol=1e-5)
    assert not np.allclose(with_nose.positions[:, J("nose")], motion.positions[:, J("nose")])
    bad = dict(mapping)
    del bad["l_wrist"]
    with pytest.raises(InputError, match="l_wrist"):
        load_motion(path, mapping=bad)
    with pytest.raises(InputError, match="unknown keys"):
        load_motion(path, mapping=dict(mapping, tail="x"))
    (tmp_path / "broken.json").write_text("{not json")
    with pytest.raises(InputError, match="JSON"):
        load_motion(path, mapping=tmp_path / "broken.json")
