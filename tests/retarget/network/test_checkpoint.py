import shutil

import numpy as np
import pytest
import torch

from pose_io import InputError
from retarget.network.checkpoint import (
    FORMAT_VERSION,
    KIND,
    load_checkpoint,
    load_official,
    load_weights,
    save_checkpoint,
)
from retarget.network.model import RetargetNet, variant_config
from retarget.network.preprocess import NormStats, PreprocessConfig


def _stats() -> NormStats:
    rng = np.random.default_rng(1)
    return NormStats(rng.normal(0, 10, (15, 2)), rng.uniform(2, 20, (15, 2)))


@pytest.mark.parametrize("variant", ["full", "skeleton", "view"])
def test_save_load_gives_identical_outputs(tmp_path, variant):
    torch.manual_seed(0)
    net = RetargetNet(variant_config(variant)).eval()
    path = save_checkpoint(tmp_path / "net.pt", net, _stats(), PreprocessConfig(output_sigma=0.0))
    loaded = load_checkpoint(path)
    assert loaded.variant == variant and loaded.training is None
    assert loaded.preprocess == PreprocessConfig(output_sigma=0.0)
    np.testing.assert_array_equal(loaded.stats.mean, _stats().mean)
    x = torch.randn(2, 30, 32)
    with torch.no_grad():
        torch.testing.assert_close(loaded.model(x), net(x), rtol=0, atol=0)
    payload = torch.load(path, weights_only=True)
    assert payload["kind"] == KIND and payload["format_version"] == FORMAT_VERSION and payload["layout"] == "body15"


def test_save_unwraps_and_leaves_no_temp_files(tmp_path):
    net = RetargetNet()
    wrapped = torch.nn.DataParallel(net)
    save_checkpoint(tmp_path / "a.pt", wrapped, _stats(), training={"epoch": 3})
    assert [p.name for p in tmp_path.iterdir()] == ["a.pt"]
    payload = torch.load(tmp_path / "a.pt", weights_only=True)
    assert not any(k.startswith("module.") for k in payload["state_dict"])
    assert load_checkpoint(tmp_path / "a.pt").training == {"epoch": 3}


def _rewrite(path, **changes):
    payload = torch.load(path, weights_only=True)
    payload.update(changes)
    torch.save(payload, path)


def test_newer_format_and_wrong_kind_are_refused(tmp_path):
    path = save_checkpoint(tmp_path / "a.pt", RetargetNet(), _stats())
    _rewrite(path, format_version=FORMAT_VERSION + 1)
    with pytest.raises(InputError, match="newer than this clone2d reads"):
        load_checkpoint(path)
    _rewrite(path, format_version=FORMAT_VERSION, kind="clone2d-reference")
    with pytest.raises(InputError, match="'clone2d-reference' checkpoint, expected 'clone2d-retarget'"):
        load_checkpoint(path)


def test_weights_that_do_not_fit_the_config(tmp_path):
    path = save_checkpoint(tmp_path / "a.pt", RetargetNet(), _stats())
    _rewrite(path, config=variant_config("skeleton").to_dict(), variant="skeleton")
    with pytest.raises(InputError, match="do not fit the skeleton network"):
        load_checkpoint(path)


def test_corrupt_missing_and_foreign_files(tmp_path):
    with pytest.raises(InputError, match="not found"):
        load_weights(tmp_path / "none.pt")
    bad = tmp_path / "bad.pt"
    bad.write_bytes(b"\x00garbage" * 10)
    with pytest.raises(InputError, match="not a readable torch weights file"):
        load_weights(bad)
    truncated = tmp_path / "cut.pt"
    data = (save_checkpoint(tmp_path / "whole.pt", RetargetNet(), _stats())).read_bytes()
    truncated.write_bytes(data[: len(data) // 2])
    with pytest.raises(InputError, match="not a readable"):
        load_weights(truncated)
    foreign = tmp_path / "foreign.pt"
    torch.save({"encoder.weight": torch.zeros(3)}, foreign)
    with pytest.raises(InputError, match="not a state dict of the authors"):
        load_weights(foreign)
    listing = tmp_path / "list.pt"
    torch.save([1, 2, 3], listing)
    with pytest.raises(InputError, match="neither a clone2d checkpoint nor"):
        load_weights(listing)


def test_official_weights_need_their_statistics(shared_dir, tmp_path):
    source = shared_dir / "official_2dmr" / "weights"
    shutil.copy(source / "pretrained_skeleton.pth", tmp_path)
    with pytest.raises(InputError, match="needs meanpose.npy and stdpose.npy next to it"):
        load_official(tmp_path / "pretrained_skeleton.pth")
    shutil.copy(source / "meanpose.npy", tmp_path)
    shutil.copy(source / "stdpose.npy", tmp_path)
    assert load_weights(tmp_path / "pretrained_skeleton.pth").variant == "skeleton"


def test_official_weights_convert_to_our_format(shared_dir, tmp_path):
    official = load_official(shared_dir / "official_2dmr" / "weights" / "pretrained_full.pth")
    path = save_checkpoint(tmp_path / "full.pt", official.model, official.stats, official.preprocess)
    again = load_weights(path)
    x = torch.randn(1, 30, 64)
    with torch.no_grad():
        torch.testing.assert_close(again.model(x), official.model(x), rtol=0, atol=0)
