"""BVH reading and forward kinematics of BVH rigs."""

from __future__ import annotations

import gzip
from pathlib import Path

import numpy as np
import pytest

from pose_io.errors import InputError
from retarget.world.mocap import axis_rotations, euler_matrices, parse_bvh, read_bvh

# A three-joint chain: Hips (6 channels, Z X Y order) -> Chest (3 channels) -> End Site.
SMALL_BVH = """HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT Chest
  {
    OFFSET 0 10 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    End Site
    {
      OFFSET 5 0 0
    }
  }
}
MOTION
Frames: 3
Frame Time: 0.0333333
1 2 3 0 0 0 0 0 0
0 0 0 0 0 90 0 0 0
0 100 0 90 0 0 0 0 90
"""


def write(path: Path, text: str, compress: bool = False) -> Path:
    if compress:
        path.write_bytes(gzip.compress(text.encode()))
    else:
        path.write_text(text)
    return path


def test_forward_kinematics_of_a_small_rig(tmp_path: Path) -> None:
    clip = read_bvh(write(tmp_path / "small.bvh", SMALL_BVH))
    assert clip.names == ("Hips", "Chest", "Chest_End")
    assert clip.parents.tolist() == [-1, 0, 1]
    assert clip.num_frames == 3 and clip.fps == pytest.approx(30.0, rel=1e-4)
    pos = clip.global_positions()
    # Frame 0: translation only.
    np.testing.assert_allclose(pos[0], [[1, 2, 3], [1, 12, 3], [6, 12, 3]], atol=1e-9)
    # Frame 1: the root turns 90 degrees about Y, which takes +X to -Z.
    np.testing.assert_allclose(pos[1], [[0, 0, 0], [0, 10, 0], [0, 10, -5]], atol=1e-9)
    # Frame 2: root 90 about Z (+Y -> -X), Chest 90 about Y (+X -> -Z, still in the root's turned frame).
    np.testing.assert_allclose(pos[2], [[0, 100, 0], [-10, 100, 0], [-10, 100, -5]], atol=1e-9)


def test_channel_order_is_respected() -> None:
    angles = np.array([[30.0, -20.0, 50.0]])
    zxy = euler_matrices(angles, "ZXY")[0]
    expected = axis_rotations(2, 30.0) @ axis_rotations(0, -20.0) @ axis_rotations(1, 50.0)
    np.testing.assert_allclose(zxy, expected, atol=1e-12)
    text = SMALL_BVH.replace("Zrotation Xrotation Yrotation\n  JOINT", "Xrotation Yrotation Zrotation\n  JOINT")
    a = parse_bvh(SMALL_BVH).global_positions()
    b = parse_bvh(text).global_positions()
    # Same numbers, other axes: frame 2's root rotation now is about X instead of Z.
    assert not np.allclose(a[2], b[2])


def test_position_channels_on_every_joint(tmp_path: Path) -> None:
    # Bandai Namco style: six channels on every joint, the position channels repeating the OFFSET.
    text = SMALL_BVH.replace(
        "    CHANNELS 3 Zrotation Xrotation Yrotation",
        "    CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation",
    )
    lines = text.splitlines()
    start = lines.index("MOTION") + 3
    for k in range(start, start + 3):
        vals = lines[k].split()
        lines[k] = " ".join(vals[:6] + ["0", "10", "0"] + vals[6:])
    clip = parse_bvh("\n".join(lines) + "\n")
    assert clip.absolute_positions.tolist() == [False, True, False]
    np.testing.assert_allclose(clip.global_positions(), parse_bvh(SMALL_BVH).global_positions(), atol=1e-9)


def test_root_position_channels_relative_to_offset() -> None:
    # iClone style: the root OFFSET holds the hip height and the channels a small displacement.
    text = SMALL_BVH.replace("ROOT Hips\n{\n  OFFSET 0 0 0", "ROOT Hips\n{\n  OFFSET 0 90 0")
    clip = parse_bvh(text)
    assert not clip.absolute_positions[0]
    np.testing.assert_allclose(clip.global_positions()[0, 0], [1, 92, 3])


def test_gzip_and_plain_read_the_same(tmp_path: Path) -> None:
    plain = read_bvh(write(tmp_path / "a.bvh", SMALL_BVH))
    packed = read_bvh(write(tmp_path / "a.bvh.gz", SMALL_BVH, compress=True))
    np.testing.assert_array_equal(plain.motion, packed.motion)
    np.testing.assert_array_equal(plain.global_positions(), packed.global_positions())


def test_fk_subset_matches_full() -> None:
    clip = parse_bvh(SMALL_BVH)
    full = clip.global_positions()
    part = clip.global_positions([1])
    np.testing.assert_array_equal(part[:, :2], full[:, :2])
    assert np.isnan(part[:, 2]).all()


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda t: t.rsplit("\n", 2)[0] + "\n", "truncated"),
        (lambda t: t.replace("0 0 0 0 0 90 0 0 0", "0 0 0 0 0 90 0 0"), "wrong channel count"),
        (lambda t: t.replace("0 0 0 0 0 90 0 0 0", "0 0 0 0 0 abc 0 0 0"), "non-numeric"),
        (lambda t: t.replace("MOTION", "MOTON"), "not a BVH"),
        (lambda t: t.replace("OFFSET 0 10 0", "OFFSET 0 ten 0"), "expected a number"),
        (lambda t: t.replace("Zrotation Xrotation Yrotation\n  JOINT", "Zrotation Xrotation Wrotation\n  JOINT"),
         "unknown channel"),
        (lambda t: t.replace("Frame Time: 0.0333333", "Frame Time: 0"), "frame time"),
        (lambda t: t.replace("    End Site\n    {\n      OFFSET 5 0 0\n    }\n  }\n}", "    End Site\n    {"),
         "hierarchy"),
    ],
)
def test_broken_files_give_one_clear_error(tmp_path: Path, edit, message: str) -> None:
    path = write(tmp_path / "broken.bvh", edit(SMALL_BVH))
    with pytest.raises(InputError, match=message) as info:
        read_bvh(path)
    assert "broken.bvh" in str(info.value) and "\n" not in str(info.value)


def test_missing_file_and_bad_gzip(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="no such file"):
        read_bvh(tmp_path / "none.bvh")
    bad = tmp_path / "bad.bvh.gz"
    bad.write_bytes(gzip.compress(SMALL_BVH.encode())[:40])
    with pytest.raises(InputError, match="gzip"):
        read_bvh(bad)
