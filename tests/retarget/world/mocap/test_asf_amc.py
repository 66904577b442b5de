"""Acclaim ASF/AMC reading: a tiny skeleton with known positions, and CMU's files against their BVH."""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np
import pytest

from pose_io.errors import InputError
from retarget.world.mocap import read_asf_amc, read_bvh

# root -> thigh (2 units down) -> shin (3 units down) -> shin_End.
TINY_ASF = """# a two-bone leg
:version 1.10
:name tiny
:units
  mass 1.0
  length 1.0
  angle {unit}
:root
   order TX TY TZ RX RY RZ
   axis XYZ
   position 0 0 0
   orientation 0 0 0
:bonedata
  begin
     id 1
     name thigh
     direction 0 -1 0
     length 2
     axis 0 0 0  XYZ
     dof rx ry rz
  end
  begin
     id 2
     name shin
     direction 0 -1 0
     length 3
     axis 0 0 0 XYZ
     dof rx
  end
:hierarchy
  begin
    root thigh
    thigh shin
  end
"""

# Frame 1: translation only. Frame 2: the root turns 90 about Y, the thigh 90 about X.
TINY_AMC = """:FULLY-SPECIFIED
:{unit}
1
root 1 2 3 0 0 0
thigh 0 0 0
shin 0
2
root 0 0 0 0 {right} 0
thigh {right} 0 0
shin 0
"""


def tiny_files(folder: Path, radians: bool = False) -> tuple[Path, Path]:
    right = f"{math.pi / 2!r}" if radians else "90"
    asf = folder / "tiny.asf"
    amc = folder / "tiny_01.amc"
    asf.write_text(TINY_ASF.format(unit="rad" if radians else "deg"))
    amc.write_text(TINY_AMC.format(unit="RADIANS" if radians else "DEGREES", right=right))
    return asf, amc


@pytest.mark.parametrize("radians", [False, True])
def test_tiny_skeleton_has_known_positions(tmp_path: Path, radians: bool) -> None:
    clip = read_asf_amc(*tiny_files(tmp_path, radians))
    assert clip.names == ("root", "thigh", "shin", "shin_End")
    assert clip.parents.tolist() == [-1, 0, 1, 2]
    assert clip.num_frames == 2 and clip.fps == pytest.approx(120.0)
    pos = clip.global_positions()
    # A joint sits at its bone's start: the thigh joint (hip) is at the root, the shin joint (knee) 2 below.
    np.testing.assert_allclose(pos[0], [[1, 2, 3], [1, 2, 3], [1, 0, 3], [1, -3, 3]], atol=1e-9)
    # Rx(90) takes the leg from -Y to -Z, then Ry(90) takes -Z to -X.
    np.testing.assert_allclose(pos[1], [[0, 0, 0], [0, 0, 0], [-2, 0, 0], [-5, 0, 0]], atol=1e-9)


def test_tiny_skeleton_errors(tmp_path: Path) -> None:
    asf, amc = tiny_files(tmp_path)
    amc.write_text(":DEGREES\n1\nroot 0 0 0 0 0 0\nshin 1 2\n")
    with pytest.raises(InputError, match="bone shin has 2 values"):
        read_asf_amc(asf, amc)
    amc.write_text(":DEGREES\n1\nroot 0 0 0\n")
    with pytest.raises(InputError, match="root lines must have 6 values"):
        read_asf_amc(asf, amc)
    asf.write_text(TINY_ASF.format(unit="deg").replace("thigh shin", "thigh knee"))
    with pytest.raises(InputError, match="unknown bone 'knee'"):
        read_asf_amc(asf, amc)
    # Each number finite, their product not: one error line, no overflow warning.
    asf.write_text(TINY_ASF.format(unit="deg").replace("direction 0 -1 0\n     length 3", "direction 0 -1e300 0\n     length 1e300"))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(InputError, match="bone shin: direction x length is out of range"):
            read_asf_amc(asf, amc)


def test_amc_matches_the_cgspeed_bvh_of_the_same_take(shared_dir: Path) -> None:
    """CMU 01_01 as Acclaim files and as cgspeed's BVH (whose frame 0 is an added T-pose)."""
    folder = shared_dir / "mocap" / "cmu_fairmotion"
    amc = read_asf_amc(folder / "01.asf", folder / "01_01.amc")
    bvh = read_bvh(folder / "01_01.bvh.gz")
    assert amc.num_frames == bvh.num_frames - 1
    pa = amc.global_positions()
    pb = bvh.global_positions()[1:]
    legs = [("LeftUpLeg", "lfemur"), ("LeftLeg", "ltibia"), ("LeftFoot", "lfoot"), ("RightToeBase", "rtoes")]
    for b, a in legs:
        np.testing.assert_allclose(pb[:, bvh.index(b)], pa[:, amc.index(a)], atol=1e-3)
    # cgspeed dropped the thorax bone, so the upper body is shifted; its limbs still agree.
    for (b0, a0), (b1, a1) in [(("LeftArm", "lhumerus"), ("LeftHand", "lwrist")), (("Neck1", "upperneck"), ("Head", "head"))]:
        vb = pb[:, bvh.index(b1)] - pb[:, bvh.index(b0)]
        va = pa[:, amc.index(a1)] - pa[:, amc.index(a0)]
        np.testing.assert_allclose(vb, va, atol=1e-3)


def test_broken_amc(tmp_path: Path, shared_dir: Path) -> None:
    asf = shared_dir / "mocap" / "cmu_fairmotion" / "01.asf"
    amc = tmp_path / "x.amc"
    amc.write_text(":FULLY-SPECIFIED\n:DEGREES\n1\nroot 0 0 0 0 0 0\nlfemur 1 2 x\n")
    with pytest.raises(InputError, match="non-numeric"):
        read_asf_amc(asf, amc)
    amc.write_text(":DEGREES\n1\nroot 0 0 0 0 0 0\nnobone 1 2 3\n")
    with pytest.raises(InputError, match="nobone"):
        read_asf_amc(asf, amc)
