"""`clone synth render` and `clone synth characters` through typer's CliRunner."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from clone.cli.main import app
from pose_io.readers import read_track
from retarget.world.characters import NAMED_CHARACTERS

# (name, parent, offset in cm): a small rig with MotionBuilder joint names (as Rokoko and most generic
# exports use), Y up, facing +Z, its left side at +X.
_RIG = (
    ("Hips", None, (0, 95, 0)),
    ("LeftUpLeg", "Hips", (10, 0, 0)), ("LeftLeg", "LeftUpLeg", (0, -43, 0)),
    ("LeftFoot", "LeftLeg", (0, -43, 0)), ("LeftToeBase", "LeftFoot", (0, -7, 13)),
    ("RightUpLeg", "Hips", (-10, 0, 0)), ("RightLeg", "RightUpLeg", (0, -43, 0)),
    ("RightFoot", "RightLeg", (0, -43, 0)), ("RightToeBase", "RightFoot", (0, -7, 13)),
    ("Spine", "Hips", (0, 10, 0)), ("Neck", "Spine", (0, 40, 0)), ("Head", "Neck", (0, 10, 0)),
    ("LeftArm", "Spine", (18, 37, 0)), ("LeftForeArm", "LeftArm", (0, -28, 0)),
    ("LeftHand", "LeftForeArm", (0, -25, 0)),
    ("RightArm", "Spine", (-18, 37, 0)), ("RightForeArm", "RightArm", (0, -28, 0)),
    ("RightHand", "RightForeArm", (0, -25, 0)),
)
_SWING = {"LeftUpLeg": 1.0, "RightUpLeg": -1.0, "LeftArm": -1.0, "RightArm": 1.0}


def write_walk_bvh(path: Path, frames: int) -> Path:
    """A tiny BVH (cm, 30 fps) of the rig swinging its legs and arms while moving forward."""
    children: dict[str | None, list[str]] = {}
    for name, parent, _ in _RIG:
        children.setdefault(parent, []).append(name)
    offsets = {name: off for name, _, off in _RIG}
    lines = ["HIERARCHY"]

    def emit(name: str, root: bool, pad: str) -> None:
        off = offsets[name]
        lines.extend([f"{pad}{'ROOT' if root else 'JOINT'} {name}", f"{pad}{{", f"{pad}  OFFSET {off[0]} {off[1]} {off[2]}",
                      f"{pad}  CHANNELS " + ("6 Xposition Yposition Zposition " if root else "3 ")
                      + "Zrotation Xrotation Yrotation"])
        for child in children.get(name, []):
            emit(child, False, pad + "  ")
        if name not in children:
            lines.extend([f"{pad}  End Site", f"{pad}  {{", f"{pad}    OFFSET 0 -5 0", f"{pad}  }}"])
        lines.append(f"{pad}}}")

    emit("Hips", True, "")
    lines += ["MOTION", f"Frames: {frames}", "Frame Time: 0.0333333"]
    for t in range(frames):
        swing = 25.0 * np.sin(2 * np.pi * t / 12)
        values = [0.0, 95.0, 3.0 * t, 0.0, 0.0, 0.0]
        for name, _, _ in _RIG[1:]:
            values += [0.0, _SWING.get(name, 0.0) * swing, 0.0]
        lines.append(" ".join(f"{v:.4f}" for v in values))
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture
def bvh(tmp_path: Path) -> Path:
    return write_walk_bvh(tmp_path / "walk.bvh", frames=10)


runner = CliRunner()


def test_render_writes_frames_poses_and_meta(bvh: Path, tmp_path: Path) -> None:
    out = tmp_path / "render"
    result = runner.invoke(app, ["synth", "render", str(bvh), "--character", "short_stocky", "--yaw", "30",
                                 "--pitch", "5", "--size", "64", "--start", "2", "--frames", "6", "--out", str(out)])
    assert result.exit_code == 0, result.output
    frames = sorted((out / "frames").iterdir())
    assert [p.name for p in frames] == [f"frame_{t:06d}.png" for t in range(6)]
    assert len(list((out / "poses").glob("*_keypoints.json"))) == 6
    meta = json.loads((out / "meta.json").read_text())
    assert meta["motion"]["source"] == str(bvh) and meta["motion"]["start"] == 2 and meta["motion"]["frames"] == 6
    assert meta["character"]["requested"] == "short_stocky" and meta["character"]["seed"] is None
    assert meta["character"]["bone_lengths_m"] == NAMED_CHARACTERS["short_stocky"].as_dict()
    assert meta["camera"]["yaw_deg"] == 30.0 and meta["size"] == [64, 64] and meta["fps"] == 30.0
    assert "FRAME_SCALE" in meta["framing"]
    # The JSON poses are the exact projected joints (inside the canvas); BODY_25's extra joints are missing.
    exact = read_track(out / "poses.npz")
    seen = read_track(out / "poses")
    assert seen.layout == "body25" and seen.num_frames == 6 and seen.image_size == (64, 64)
    visible = ~seen.missing
    assert visible.any()
    np.testing.assert_array_equal(seen.joints[visible], exact.joints[visible])
    assert seen.missing[:, seen.joint_layout.index("l_ear")].all()
    assert not exact.missing[:, exact.joint_layout.index("r_big_toe")].any()
    assert not list(tmp_path.glob(".render*")), "temporary folders left behind"


def test_render_with_a_seed_character(bvh: Path, tmp_path: Path) -> None:
    out = tmp_path / "seeded"
    result = runner.invoke(app, ["synth", "render", str(bvh), "--character", "17", "--size", "48", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert len(list((out / "frames").iterdir())) == 10
    meta = json.loads((out / "meta.json").read_text())
    assert meta["character"]["seed"] == 17 and meta["character"]["skeleton"] == "seed:17"


def test_render_refuses_an_existing_output(bvh: Path, tmp_path: Path) -> None:
    out = tmp_path / "taken"
    out.mkdir()
    (out / "mine.txt").write_text("keep me")
    result = runner.invoke(app, ["synth", "render", str(bvh), "--size", "32", "--out", str(out)])
    assert result.exit_code == 2
    assert "already exists" in result.output
    assert [p.name for p in out.iterdir()] == ["mine.txt"]


def test_render_unknown_character_lists_the_valid_names(bvh: Path, tmp_path: Path) -> None:
    out = tmp_path / "never"
    result = runner.invoke(app, ["synth", "render", str(bvh), "--character", "giant", "--out", str(out)])
    assert result.exit_code == 2
    assert "unknown character 'giant'" in result.output
    for name in NAMED_CHARACTERS:
        assert name in result.output
    assert not out.exists()


def test_render_missing_motion_file(tmp_path: Path) -> None:
    out = tmp_path / "never"
    result = runner.invoke(app, ["synth", "render", str(tmp_path / "nope.bvh"), "--out", str(out)])
    assert result.exit_code == 2
    assert "nope.bvh" in result.output and "Traceback" not in result.output
    assert not out.exists()


def test_render_frame_range_outside_the_motion(bvh: Path, tmp_path: Path) -> None:
    out = tmp_path / "never"
    result = runner.invoke(app, ["synth", "render", str(bvh), "--start", "8", "--frames", "5", "--out", str(out)])
    assert result.exit_code == 2 and "--frames 5" in result.output
    assert not out.exists()


def test_characters_lists_every_named_character() -> None:
    result = runner.invoke(app, ["synth", "characters"])
    assert result.exit_code == 0, result.output
    for name, skeleton in NAMED_CHARACTERS.items():
        line = next(line for line in result.output.splitlines() if line.startswith(name + " "))
        assert f"height {skeleton.height:.2f} m" in line


def test_render_twice_gives_identical_files(bvh: Path, tmp_path: Path) -> None:
    outs = [tmp_path / "a", tmp_path / "b"]
    for out in outs:
        result = runner.invoke(app, ["synth", "render", str(bvh), "--character", "child", "--yaw", "-60",
                                     "--size", "40", "--out", str(out)])
        assert result.exit_code == 0, result.output
    files = sorted(p.relative_to(outs[0]) for p in outs[0].rglob("*") if p.is_file())
    assert len(files) > 20
    assert files == sorted(p.relative_to(outs[1]) for p in outs[1].rglob("*") if p.is_file())
    for rel in files:  # frames, poses and meta alike
        assert (outs[0] / rel).read_bytes() == (outs[1] / rel).read_bytes(), rel
