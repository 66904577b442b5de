"""retarget.training.run: training from folders on disk (motion capture, OpenPose tracks)."""

from __future__ import annotations

import shutil

import pytest

from pose_io import InputError
from retarget.network.checkpoint import load_checkpoint
from retarget.training.run import train
from tests.retarget.training.fake_split import TINY


def test_train_on_a_motion_world_built_from_mocap(shared_dir, tmp_path):
    mocap = tmp_path / "mocap"
    mocap.mkdir()
    for name in ("dataset-1/dataset-1_walk_normal_001", "dataset-1/dataset-1_bow_normal_001",
                 "dataset-2/dataset-2_walk_normal_001", "dataset-2/dataset-2_walk_normal_002"):
        shutil.copy(shared_dir / "mocap" / "bandai_namco" / f"{name}.bvh.gz", mocap)
    summary = train(mocap, tmp_path / "r.pt", cache_dir=tmp_path / "cache", config=TINY, epochs=1,
                    best=tmp_path / "best.pt")
    assert summary.epochs == 1 and "val_cross" in summary.history[0]
    assert load_checkpoint(tmp_path / "r.pt").training["epoch"] == 1
    assert summary.best_epoch == 1 and load_checkpoint(tmp_path / "best.pt").training is None


def test_real_tracks_are_read_from_openpose_folders(shared_dir, tmp_path):
    from retarget.training.run import read_real_tracks

    for clip in ("tall_man", "small_man"):
        shutil.copytree(shared_dir / "openpose_examples" / clip, tmp_path / "real" / clip)
    tracks = read_real_tracks(tmp_path / "real")
    assert [len(t) for t in tracks] == [121, 135]  # sorted by folder name
    assert len(read_real_tracks(tmp_path / "real" / "tall_man")) == 1
    (tmp_path / "empty").mkdir()
    with pytest.raises(InputError, match="no OpenPose folders"):
        read_real_tracks(tmp_path / "empty")
