"""retarget.training.blend: a weight-by-weight blend of two checkpoints of one network."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from pose_io.errors import InputError
from retarget.network.checkpoint import load_checkpoint, save_checkpoint
from retarget.network.model import RetargetNet, variant_config
from retarget.network.preprocess import NormStats
from retarget.training.blend import blend_checkpoints, main


def _net(seed: int, tmp_path, name: str, std: float = 50.0):
    torch.manual_seed(seed)
    return save_checkpoint(tmp_path / name, RetargetNet(variant_config("full")),
                           NormStats(np.zeros((15, 2)), np.full((15, 2), std)))  # fmt: skip


def test_a_blend_lies_on_the_line_between_the_two(tmp_path) -> None:
    a, b = _net(0, tmp_path, "a.pt"), _net(1, tmp_path, "b.pt")
    wa, wb = load_checkpoint(a).model.state_dict(), load_checkpoint(b).model.state_dict()
    for share in (0.0, 0.3, 1.0):
        out = load_checkpoint(blend_checkpoints(a, b, share, tmp_path / f"mix{share}.pt")).model.state_dict()
        for key, value in out.items():
            if value.is_floating_point():
                torch.testing.assert_close(value, (1 - share) * wa[key] + share * wb[key])
            else:
                assert torch.equal(value, wa[key])
    assert any(not torch.equal(v, wb[k]) for k, v in wa.items())  # two different networks were blended


def test_blends_of_other_networks_or_statistics_and_bad_shares_are_refused(tmp_path, capsys) -> None:
    a, b = _net(0, tmp_path, "a.pt"), _net(1, tmp_path, "b.pt")
    other_stats = _net(1, tmp_path, "c.pt", std=40.0)
    with pytest.raises(InputError, match="statistics"):
        blend_checkpoints(a, other_stats, 0.5, tmp_path / "x.pt")
    torch.manual_seed(0)
    small = save_checkpoint(tmp_path / "s.pt", RetargetNet(variant_config("skeleton")),
                            NormStats(np.zeros((15, 2)), np.full((15, 2), 50.0)))  # fmt: skip
    with pytest.raises(InputError, match="configuration"):
        blend_checkpoints(a, small, 0.5, tmp_path / "x.pt")
    with pytest.raises(InputError, match="share"):
        blend_checkpoints(a, b, 1.5, tmp_path / "x.pt")
    assert not (tmp_path / "x.pt").exists()
    before = a.read_bytes()
    for args in ([str(a), str(b), "--share", "0.5", "--out", str(a)],
                 [str(a), str(b), "--share", "0.5", "--out", str(b)],
                 [str(a), str(b), "--share", "-1", "--out", str(tmp_path / "y.pt")]):
        with pytest.raises(SystemExit) as exit_:
            main(args)
        assert exit_.value.code == 2 and capsys.readouterr().err.count("error:") == 1
    assert a.read_bytes() == before and not (tmp_path / "y.pt").exists()
    assert main([str(a), str(b), "--share", "0.5", "--out", str(tmp_path / "y.pt")]) == 0
    with pytest.raises(SystemExit):  # exists
        main([str(a), str(b), "--share", "0.5", "--out", str(tmp_path / "y.pt")])
    assert main([str(a), str(b), "--share", "0.5", "--out", str(tmp_path / "y.pt"), "--overwrite"]) == 0


def test_the_shipped_weights_are_the_documented_blend(tmp_path) -> None:
    from pathlib import Path

    from retarget.api import PACKAGED_WEIGHTS

    root = Path(__file__).resolve().parents[3] / "checkpoints"
    run6, run7 = root / "retarget_run6_mean.pt", root / "retarget_run7.pt"
    if not (run6.is_file() and run7.is_file()):
        pytest.skip("the run checkpoints are not in this checkout")
    out = load_checkpoint(blend_checkpoints(run6, run7, 0.3, tmp_path / "mix.pt")).model.state_dict()
    shipped = load_checkpoint(PACKAGED_WEIGHTS).model.state_dict()
    for key, value in shipped.items():
        torch.testing.assert_close(out[key], value)
