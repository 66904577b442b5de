"""retarget.network.numpy_weights and the backend choice of load_retargeter.

The first test keeps the packaged pair honest: whoever replaces retarget/weights/clone2d_full.pt must regenerate
clone2d_full.npz (`python -m retarget.network.numpy_weights`), or this fails.
"""

from __future__ import annotations

import numpy as np
import pytest
import torch

from pose_io.errors import InputError
from retarget import api
from retarget.api import InferenceConfig, NumpyRetargeter, Retargeter, load_retargeter
from retarget.network.checkpoint import load_weights, save_checkpoint
from retarget.network.model import RetargetNet, variant_config
from retarget.network.numpy_weights import current_export, export_npz, file_sha256, main, npz_beside, read_npz
from retarget.network.preprocess import NormStats, PreprocessConfig


def test_the_packaged_export_is_the_packaged_checkpoint():
    npz = npz_beside(api.PACKAGED_WEIGHTS)
    assert npz.is_file(), f"regenerate it: python -m retarget.network.numpy_weights ({npz.name} is missing)"
    export, checkpoint = read_npz(npz), load_weights(api.PACKAGED_WEIGHTS)
    assert export.source_sha256 == file_sha256(api.PACKAGED_WEIGHTS), (
        f"{npz.name} was exported from another {api.PACKAGED_WEIGHTS.name}; run python -m retarget.network.numpy_weights")
    assert export.model.config == checkpoint.model.config and export.preprocess == checkpoint.preprocess
    np.testing.assert_array_equal(export.stats.mean, checkpoint.stats.mean)
    np.testing.assert_array_equal(export.stats.std, checkpoint.stats.std)
    with np.load(npz) as data:
        for name, value in checkpoint.model.state_dict().items():
            np.testing.assert_array_equal(data[name], value.numpy(), err_msg=name)
    assert current_export(api.PACKAGED_WEIGHTS) is not None


@pytest.fixture
def checkpoint(tmp_path):
    torch.manual_seed(0)
    stats = NormStats(np.zeros((15, 2)), np.ones((15, 2)))
    return save_checkpoint(tmp_path / "mine.pt", RetargetNet(variant_config("full")), stats,
                           PreprocessConfig(body_height=150.0))


def test_export_round_trip_and_staleness(checkpoint, tmp_path):
    assert current_export(checkpoint) is None  # nothing written beside a user's file unless asked
    npz = export_npz(checkpoint)
    assert npz == tmp_path / "mine.npz"
    export = current_export(checkpoint)
    assert export is not None and export.preprocess.body_height == 150.0 and export.variant == "full"
    torch.manual_seed(1)  # the checkpoint changes: its old export is stale and ignored
    save_checkpoint(checkpoint, RetargetNet(variant_config("full")), NormStats(np.zeros((15, 2)), np.ones((15, 2))))
    assert current_export(checkpoint) is None
    assert main([str(checkpoint)]) == 0
    assert current_export(checkpoint) is not None


def test_foreign_or_broken_files_are_refused(tmp_path):
    np.savez(tmp_path / "track.npz", joints=np.zeros((3, 15, 2)))
    (tmp_path / "broken.npz").write_bytes(b"not a zip")
    for name in ("track.npz", "broken.npz"):
        with pytest.raises(InputError, match="not a clone2d numpy weights file"):
            read_npz(tmp_path / name)
    with pytest.raises(InputError, match="not found"):
        read_npz(tmp_path / "missing.npz")
    (tmp_path / "track.pt").write_bytes(b"whatever")
    assert current_export(tmp_path / "track.pt") is None  # a foreign .npz beside it is ignored


def test_backend_choice(checkpoint):
    assert isinstance(load_retargeter(checkpoint), Retargeter)  # the library's default stays torch
    assert isinstance(load_retargeter(checkpoint, backend="auto"), Retargeter)  # no export yet
    with pytest.raises(InputError, match="no up-to-date numpy export"):
        load_retargeter(checkpoint, backend="numpy")
    npz = export_npz(checkpoint)
    plain = InferenceConfig(refine_steps=0)
    for backend in ("auto", "numpy"):
        assert isinstance(load_retargeter(checkpoint, "auto", plain, backend=backend), NumpyRetargeter)
        assert isinstance(load_retargeter(npz, "cpu", backend=backend), NumpyRetargeter)  # an export: numpy
    # numpy refines motion codes too: auto takes it for the default config as well
    assert isinstance(load_retargeter(checkpoint, "auto", backend="auto"), NumpyRetargeter)
    assert load_retargeter(checkpoint, "auto", backend="numpy").config.refine_steps == InferenceConfig().refine_steps
    assert isinstance(load_retargeter(checkpoint, "cpu", backend="torch"), Retargeter)
    with pytest.raises(InputError, match="runs on the CPU"):
        load_retargeter(checkpoint, "cuda", backend="numpy")
    with pytest.raises(InputError, match="numpy export runs on the CPU"):
        load_retargeter(npz, "cpu", backend="torch")
    with pytest.raises(InputError, match="unknown backend 'onnx'; valid: auto, numpy, torch"):
        load_retargeter(checkpoint, backend="onnx")


def test_the_packaged_weights_run_without_torch_by_choice():
    assert isinstance(load_retargeter(config=InferenceConfig(refine_steps=0), backend="auto"), NumpyRetargeter)
