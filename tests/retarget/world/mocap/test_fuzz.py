"""Garbage in, InputError out: the BVH and ASF/AMC readers never raise anything else (fuzzed with hypothesis)."""

from __future__ import annotations

import gzip

import numpy as np
import pytest
from hypothesis import event, given
from hypothesis import strategies as st

from pose_io.errors import InputError
from retarget.world.mocap import parse_bvh, read_asf_amc, read_bvh
from tests.pose_io.fuzzing import fast_and_slow, mutated_text
from tests.retarget.world.mocap.test_asf_amc import TINY_AMC, TINY_ASF
from tests.retarget.world.mocap.test_bvh import SMALL_BVH

# Tokens that mean something to a BVH parser, besides the hostile numbers.
_BVH_TOKENS = ["ROOT", "JOINT", "End", "Site", "OFFSET", "CHANNELS", "MOTION", "HIERARCHY", "Frames:", "Frame",
               "Time:", "Xposition", "Zrotation", "{", "}", "0", "3", "6", "64", "65", "-1", "1e308", "nan", "inf",
               "1e400", "9" * 5000, "\n", "MOTION\n", "\x00"]


def _deep(levels: int) -> str:
    """A hierarchy nested ``levels`` joints deep (more than Python's recursion limit when large)."""
    opening = "".join(f"JOINT j{i}\n{{\nOFFSET 0 1 0\nCHANNELS 1 Zrotation\n" for i in range(levels))
    return (f"HIERARCHY\nROOT r\n{{\nOFFSET 0 0 0\nCHANNELS 1 Zrotation\n{opening}" + "}\n" * (levels + 1)
            + f"MOTION\nFrames: 1\nFrame Time: 0.1\n{' '.join(['0'] * (levels + 1))}\n")


_bvh_texts = (
    mutated_text(SMALL_BVH, tokens=_BVH_TOKENS, max_edits=6)
    | st.text(max_size=200)
    | st.sampled_from([1, 10, 2000, 5000]).map(_deep)
    | st.builds(lambda body, n: SMALL_BVH.replace("Frames: 3", f"Frames: {n}").replace(
        "1 2 3 0 0 0 0 0 0\n", body), st.text(alphabet="0123456789 .-e\n", max_size=60),
        st.sampled_from(["3", "0", "-1", "1e3", "99999999999999999999", "9" * 5000]))
)


def _parse_case(text: str) -> None:
    try:
        clip = parse_bvh(text, "fuzz.bvh")
    except InputError as exc:
        assert "\n" not in str(exc) and str(exc).startswith("fuzz.bvh")
        event("InputError")
        return
    event("clip")
    assert clip.motion.shape == (clip.num_frames, sum(len(c) for c in clip.channels))
    assert np.isfinite(clip.motion).all()


test_parse_bvh_fuzz, test_parse_bvh_fuzz_slow = fast_and_slow(lambda: given(text=_bvh_texts)(_parse_case), fast=150)


def _read_case(tmp_path_factory: pytest.TempPathFactory, raw: bytes, compress: bool) -> None:
    path = tmp_path_factory.mktemp("bvh") / "clip.bvh"
    path.write_bytes(gzip.compress(raw)[: len(raw) + 10] if compress else raw)
    try:
        read_bvh(path)
    except InputError as exc:
        assert "\n" not in str(exc) and str(path) in str(exc)


test_read_bvh_bytes_fuzz, test_read_bvh_bytes_fuzz_slow = fast_and_slow(
    lambda: given(raw=_bvh_texts.map(lambda t: t.encode("utf-8", "surrogatepass")) | st.binary(max_size=300),
                  compress=st.booleans())(_read_case), fast=40)


def test_deep_hierarchy_is_an_input_error() -> None:
    with pytest.raises(InputError, match="nested deeper than"):
        parse_bvh(_deep(5000), "deep.bvh")
    assert parse_bvh(_deep(10), "ok.bvh").names[-1] == "j9"


def test_unreadable_bvh_is_an_input_error(tmp_path) -> None:
    (tmp_path / "folder.bvh").mkdir()
    with pytest.raises(InputError, match="folder.bvh"):
        read_bvh(tmp_path / "folder.bvh")
    (tmp_path / "link.bvh").symlink_to(tmp_path / "nowhere")
    with pytest.raises(InputError, match="link.bvh"):
        read_bvh(tmp_path / "link.bvh")


_ASF = TINY_ASF.format(unit="deg")
_AMC = TINY_AMC.format(unit="DEGREES", right="90")


def _asf_case(tmp_path_factory: pytest.TempPathFactory, asf: str, amc: str, fps: float) -> None:
    folder = tmp_path_factory.mktemp("asf")
    (folder / "a.asf").write_text(asf, errors="surrogatepass")
    (folder / "a.amc").write_text(amc, errors="surrogatepass")
    try:
        clip = read_asf_amc(folder / "a.asf", folder / "a.amc", fps=fps)
    except InputError as exc:
        assert "\n" not in str(exc)
        event("InputError")
        return
    event("clip")
    assert np.isfinite(clip.root_positions).all()


test_asf_amc_fuzz, test_asf_amc_fuzz_slow = fast_and_slow(
    lambda: given(asf=mutated_text(_ASF), amc=mutated_text(_AMC),
                  fps=st.sampled_from([120.0, 30.0, 0.0, -1.0, float("nan")]))(_asf_case), fast=40)
