"""From folders on disk to a trained checkpoint: read real tracks, build the motion world, :func:`fit` on it."""

from __future__ import annotations

from pathlib import Path

import torch

from pose_io.errors import InputError
from retarget.network.checkpoint import load_weights
from retarget.training import distributed
from retarget.training.config import DEFAULT_CONFIG, TrainConfig
from retarget.training.loop import CPU, TrainSummary, fit
from retarget.training.state import ProgressFn, require_new


def read_real_tracks(folder: str | Path, named: bool = False) -> list:
    """Every OpenPose folder in ``folder`` (or ``folder`` itself when it holds the JSON files).

    Returns:
        the tracks, or ``(folder name, track)`` pairs with ``named``.
    """
    from pose_io.readers import read_track

    folder = Path(folder)
    if not folder.is_dir():
        raise InputError(f"{folder}: not a folder of OpenPose folders")
    if any(folder.glob("*_keypoints.json")):
        subfolders = [folder]
    else:
        subfolders = sorted(p for p in folder.iterdir() if p.is_dir() and any(p.glob("*_keypoints.json")))
    if not subfolders:
        raise InputError(f"{folder}: no OpenPose folders (*_keypoints.json) in it")
    tracks = [read_track(p, fmt="openpose") for p in subfolders]
    return [(p.name, t) for p, t in zip(subfolders, tracks)] if named else tracks


def train(
    mocap_dir: str | Path,
    out: str | Path,
    *,
    cache_dir: str | Path | None = None,
    real_dir: str | Path | None = None,
    config: TrainConfig = DEFAULT_CONFIG,
    device: torch.device = CPU,
    epochs: int | None = None,
    minutes: float | None = None,
    resume: bool = False,
    num_workers: int = 0,
    progress: ProgressFn | None = None,
    init: str | Path | None = None,
    amp: bool | None = None,
    best: str | Path | None = None,
    average: str | Path | None = None,
    average_from: int | None = None,
) -> TrainSummary:
    """Build (or reuse the cache of) the motion world from ``mocap_dir`` and :func:`fit` on it.

    Under ``torchrun`` every process calls this (see :func:`fit`); the first process of each machine builds
    the world's cache while the others wait, then they read it.

    Args:
        mocap_dir: motion-capture folder the world is built from.
        out: checkpoint file.
        cache_dir: where the world is cached (default: the world's, ``~/.cache/clone2d/world``).
        real_dir: optional folder of OpenPose folders (unlabelled real tracks).
        config: training settings.
        device: where to train.
        epochs: total epochs (see :func:`fit`).
        minutes: time budget of this call.
        resume: continue the run in ``out``.
        num_workers: data-loader worker processes (cutting world windows overlaps the network's work).
        progress: callback (see :func:`fit`).
        init: checkpoint to start from: ours, or the authors' ``pretrained_*.pth`` with its statistics.
        amp: bfloat16 autocast on CUDA (see :func:`fit`).
        best: file for the weights of the epoch with the lowest validation retargeting error (see :func:`fit`).
        average, average_from: file for the mean of the weights from that epoch on (see :func:`fit`).
    """
    from retarget.world import MotionWorld

    out = Path(out)
    if resume and not out.exists():
        raise InputError(f"{out}: nothing to resume (no such checkpoint)")
    if not resume:
        require_new(out)
    start = load_weights(init) if init is not None and not resume else None
    real = read_real_tracks(real_dir) if real_dir is not None else []
    with distributed.main_first():
        world = MotionWorld.build(mocap_dir, cache_dir, seed=config.seed, extra_train_characters=config.extra_characters,
                                  extra_spread=config.extra_spread)  # fmt: skip
    return fit(
        world.split("train"), world.split("val"), out, config, device, real, epochs, minutes, resume,
        num_workers=num_workers, progress=progress, init=start, amp=amp, best=best,
        average=average, average_from=average_from,
    )
