"""Retargeting checkpoints: ONE file that rebuilds the network, its statistics and preprocessing.

Layout of the file (``torch.save`` of a plain dict, read with ``weights_only=True``)::

    format_version  int, FORMAT_VERSION when written
    kind            "clone2d-retarget"
    variant         "full" | "skeleton" | "view"
    layout          "body15"
    config          NetworkConfig.to_dict()
    preprocess      PreprocessConfig as a dict
    state_dict      the unwrapped network's state dict
    stats           {"mean": [15, 2] float64 tensor, "std": [15, 2] float64 tensor}
    training        optional: what `retarget.training` needs to resume (optimizer, epoch, RNG states, ...)

The authors' released ``pretrained_*.pth`` state dicts load too (:func:`load_official`), with the
``meanpose*.npy`` / ``stdpose*.npy`` statistics that sit next to them.
"""

from __future__ import annotations

import dataclasses
import logging
import pickle
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import nn

from pose_io.atomic import atomic_file
from pose_io.errors import InputError
from retarget.network.model import VARIANTS, NetworkConfig, RetargetNet, map_official_state_dict
from retarget.network.preprocess import LAYOUT, NormStats, PreprocessConfig

log = logging.getLogger(__name__)

FORMAT_VERSION = 1
KIND = "clone2d-retarget"

# Statistics files the authors ship next to their weights, per variant.
OFFICIAL_STATS: dict[str, tuple[str, str]] = {
    "full": ("meanpose_with_view.npy", "stdpose_with_view.npy"),
    "view": ("meanpose_with_view.npy", "stdpose_with_view.npy"),
    "skeleton": ("meanpose.npy", "stdpose.npy"),
}


@dataclass(frozen=True, eq=False)
class RetargetWeights:
    """Everything a checkpoint rebuilds.

    Attributes:
        model: the network, in eval mode, on the CPU.
        stats: normalisation statistics of its input.
        preprocess: canvas height and smoothing the network was trained with.
        training: resume state written by training, or None.
        path: where it was read from.
    """

    model: RetargetNet
    stats: NormStats
    preprocess: PreprocessConfig
    training: dict[str, Any] | None
    path: Path

    @property
    def variant(self) -> str:
        return self.model.variant


def unwrap(model: nn.Module) -> nn.Module:
    """The plain module under DataParallel / DDP (``.module``) or ``torch.compile`` (``._orig_mod``)."""
    while True:
        inner = getattr(model, "_orig_mod", None)
        if inner is None:
            inner = getattr(model, "module", None)
        if not isinstance(inner, nn.Module):
            return model
        model = inner


def save_checkpoint(
    path: str | Path,
    model: nn.Module,
    stats: NormStats,
    preprocess: PreprocessConfig | None = None,
    training: dict[str, Any] | None = None,
) -> Path:
    """Write a checkpoint atomically (temp file + rename), replacing ``path``.

    Args:
        path: output file.
        model: a :class:`RetargetNet`, possibly wrapped.
        stats: its input statistics.
        preprocess: its canvas and smoothing settings (default: the authors').
        training: optional resume state (plain values and tensors only).

    Returns:
        ``path``.
    """
    net = unwrap(model)
    if not isinstance(net, RetargetNet):
        raise TypeError(f"expected a RetargetNet, got {type(net).__name__}")
    payload = {
        "format_version": FORMAT_VERSION,
        "kind": KIND,
        "variant": net.variant,
        "layout": LAYOUT.name,
        "config": net.config.to_dict(),
        "preprocess": dataclasses.asdict(preprocess or PreprocessConfig()),
        "state_dict": {k: v.detach().cpu().clone() for k, v in net.state_dict().items()},
        "stats": {"mean": torch.tensor(stats.mean), "std": torch.tensor(stats.std)},
    }
    if training is not None:
        payload["training"] = training
    path = Path(path)
    with atomic_file(path) as tmp:
        torch.save(payload, tmp)
    log.info("saved retargeting checkpoint %s", path)
    return path


def _read(path: Path) -> Any:
    if not path.is_file():
        raise InputError(f"{path}: weights file not found")
    try:
        return torch.load(path, map_location="cpu", weights_only=True)
    except (pickle.UnpicklingError, zipfile.BadZipFile, RuntimeError, EOFError, ValueError, OSError) as exc:
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise InputError(f"{path}: not a readable torch weights file ({first[:120]})") from None


def _build(path: Path, config: NetworkConfig, state_dict: dict[str, torch.Tensor]) -> RetargetNet:
    model = RetargetNet(config)
    try:
        model.load_state_dict(state_dict, strict=True)
    except RuntimeError as exc:
        first = str(exc).strip().splitlines()[0]
        raise InputError(f"{path}: weights do not fit the {config.variant} network ({first[:160]})") from None
    return model.eval()


def load_checkpoint(path: str | Path) -> RetargetWeights:
    """Read a clone2d retargeting checkpoint.

    Raises:
        InputError: missing or corrupt file, another kind of file, a newer format, or weights that do not
            fit the recorded architecture.
    """
    path = Path(path)
    return _from_payload(path, _read(path))


def _from_payload(path: Path, payload: Any) -> RetargetWeights:
    if not isinstance(payload, dict) or "kind" not in payload:
        raise InputError(f"{path}: not a clone2d retargeting checkpoint")
    if payload["kind"] != KIND:
        raise InputError(f"{path}: a {payload['kind']!r} checkpoint, expected {KIND!r}")
    version = payload.get("format_version")
    if not isinstance(version, int) or version > FORMAT_VERSION:
        raise InputError(
            f"{path}: checkpoint format {version} is newer than this clone2d reads ({FORMAT_VERSION}); upgrade clone2d"
        )
    if payload.get("layout") != LAYOUT.name:
        raise InputError(f"{path}: checkpoint joint layout {payload.get('layout')!r}, expected {LAYOUT.name!r}")
    try:
        config = NetworkConfig.from_dict(payload["config"])
        preprocess = PreprocessConfig(**payload["preprocess"])
        stats = NormStats(payload["stats"]["mean"].numpy(), payload["stats"]["std"].numpy())
        state_dict = payload["state_dict"]
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise InputError(f"{path}: incomplete or damaged checkpoint ({exc})") from None
    if payload.get("variant") != config.variant:
        raise InputError(f"{path}: checkpoint says variant {payload.get('variant')!r}, its config is {config.variant!r}")
    model = _build(path, config, state_dict)
    return RetargetWeights(model, stats, preprocess, payload.get("training"), path)


def load_official(path: str | Path) -> RetargetWeights:
    """Read one of the authors' ``pretrained_{full,skeleton,view}.pth`` with its statistics.

    The statistics are the ``.npy`` files next to the weights: ``meanpose_with_view.npy`` and
    ``stdpose_with_view.npy`` for the full and view models, ``meanpose.npy`` / ``stdpose.npy`` for the
    skeleton model.

    Raises:
        InputError: not the authors' state dict, statistics missing, or weights that do not fit.
    """
    path = Path(path)
    return _from_official(path, _read(path))


def _from_official(path: Path, state_dict: Any) -> RetargetWeights:
    if not isinstance(state_dict, dict) or not all(isinstance(v, torch.Tensor) for v in state_dict.values()):
        raise InputError(f"{path}: neither a clone2d checkpoint nor a state dict of the authors' models")
    try:
        variant, mapped = map_official_state_dict(state_dict)
    except ValueError as exc:
        raise InputError(f"{path}: {exc}") from None
    mean_name, std_name = OFFICIAL_STATS[variant]
    files = [path.parent / mean_name, path.parent / std_name]
    missing = [f.name for f in files if not f.is_file()]
    if missing:
        raise InputError(f"{path}: the authors' {variant} model needs {' and '.join(missing)} next to it")
    try:
        stats = NormStats(np.load(files[0]), np.load(files[1]))
    except (ValueError, OSError) as exc:
        raise InputError(f"{files[0].parent}: unreadable statistics next to the weights ({exc})") from None
    model = _build(path, VARIANTS[variant], mapped)
    return RetargetWeights(model, stats, PreprocessConfig(), None, path)


def load_weights(path: str | Path) -> RetargetWeights:
    """Read a clone2d checkpoint or one of the authors' state dicts, whichever ``path`` holds."""
    path = Path(path)
    payload = _read(path)
    if isinstance(payload, dict) and "kind" in payload:
        return _from_payload(path, payload)
    return _from_official(path, payload)
