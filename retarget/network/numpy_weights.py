"""The torch-free weights file: a retargeting checkpoint's network, statistics and settings as a plain ``.npz``.

Written from a checkpoint (clone2d's ``.pt`` or the authors' ``.pth``) and kept next to it with the same stem;
``clone retarget apply --refine-steps 0`` then runs without torch (:class:`retarget.api.NumpyRetargeter`). Regenerate the
packaged one after replacing ``retarget/weights/clone2d_full.pt``::

    python -m retarget.network.numpy_weights                  # packaged weights -> retarget/weights/clone2d_full.npz
    python -m retarget.network.numpy_weights W.pt --out W.npz

The file records the SHA-256 of the checkpoint it came from; an export whose checkpoint has changed since is
stale and is not used (a test checks the packaged pair).

Layout (``numpy.savez``, read with ``allow_pickle=False``)::

    meta        JSON: format, format_version, variant, config (NetworkConfig.to_dict()), preprocess,
                source (file name), source_sha256
    stats_mean  [15, 2] float64;  stats_std  [15, 2] float64
    <name>      every entry of the network's state_dict (names contain a dot), float32
"""

from __future__ import annotations

import argparse
import dataclasses
import hashlib
import json
import logging
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pose_io.atomic import atomic_file
from pose_io.errors import InputError
from retarget.network.config import NetworkConfig
from retarget.network.numpy_net import NumpyRetargetNet
from retarget.network.packaged import PACKAGED_WEIGHTS
from retarget.network.preprocess import NormStats, PreprocessConfig

log = logging.getLogger(__name__)

FORMAT = "clone2d-retarget-numpy"
FORMAT_VERSION = 1


@dataclass(frozen=True, eq=False)
class NumpyWeights:
    """What a numpy weights file rebuilds.

    Attributes:
        model: the network.
        stats: its input statistics.
        preprocess: canvas and smoothing settings.
        path: the file.
        source_sha256: SHA-256 of the checkpoint it was exported from.
    """

    model: NumpyRetargetNet
    stats: NormStats
    preprocess: PreprocessConfig
    path: Path
    source_sha256: str

    @property
    def variant(self) -> str:
        return self.model.variant


def file_sha256(path: str | Path) -> str:
    """Hex SHA-256 of a file's bytes."""
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def npz_beside(weights: str | Path) -> Path:
    """Where the export of ``weights`` lives: the same folder and stem, ``.npz``."""
    return Path(weights).with_suffix(".npz")


def export_npz(weights: str | Path, out: str | Path | None = None) -> Path:
    """Write the numpy weights file of a checkpoint (needs torch), atomically, replacing ``out``.

    Args:
        weights: a clone2d checkpoint or one of the authors' ``pretrained_*.pth`` (statistics beside it).
        out: the file to write; default :func:`npz_beside` ``weights``.

    Returns:
        ``out``.
    """
    from retarget.network.checkpoint import load_weights

    weights = Path(weights)
    out = Path(out) if out is not None else npz_beside(weights)
    loaded = load_weights(weights)
    meta = {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "variant": loaded.variant,
        "config": loaded.model.config.to_dict(),
        "preprocess": dataclasses.asdict(loaded.preprocess),
        "source": weights.name,
        "source_sha256": file_sha256(weights),
    }
    arrays = {k: v.detach().cpu().numpy().astype(np.float32) for k, v in loaded.model.state_dict().items()}
    with atomic_file(out, overwrite=True) as tmp, open(tmp, "wb") as f:
        np.savez(f, meta=np.array(json.dumps(meta)), stats_mean=loaded.stats.mean, stats_std=loaded.stats.std,
                 **arrays)  # fmt: skip
    log.info("wrote %s from %s", out, weights)
    return out


def read_npz(path: str | Path) -> NumpyWeights:
    """Read a numpy weights file.

    Raises:
        InputError: missing, corrupt or foreign file, a newer format, or parameters that do not fit.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: weights file not found")
    try:
        with np.load(path, allow_pickle=False) as data:
            meta = json.loads(str(data["meta"][()]))
            arrays = {k: data[k] for k in data.files if k != "meta"}
    except (KeyError, ValueError, OSError, zipfile.BadZipFile, json.JSONDecodeError, EOFError) as exc:
        raise InputError(f"{path}: not a clone2d numpy weights file ({type(exc).__name__})") from None
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        raise InputError(f"{path}: not a clone2d numpy weights file")
    version = meta.get("format_version")
    if not isinstance(version, int) or version > FORMAT_VERSION:
        raise InputError(f"{path}: numpy weights format {version} is newer than this clone2d reads ({FORMAT_VERSION})")
    try:
        config = NetworkConfig.from_dict(meta["config"])
        preprocess = PreprocessConfig(**meta["preprocess"])
        stats = NormStats(arrays.pop("stats_mean"), arrays.pop("stats_std"))
        model = NumpyRetargetNet(config, arrays)
        sha = str(meta["source_sha256"])
    except (KeyError, TypeError, ValueError) as exc:
        raise InputError(f"{path}: incomplete or damaged numpy weights ({exc})") from None
    return NumpyWeights(model, stats, preprocess, path, sha)


def current_export(weights: str | Path) -> NumpyWeights | None:
    """The export beside ``weights`` when there is one and it was made from these very bytes; else None.

    A stale export (the checkpoint changed since) or an unreadable one is logged and ignored.
    """
    npz = npz_beside(weights)
    if not npz.is_file() or not Path(weights).is_file() or Path(weights).suffix.lower() == ".npz":
        return None
    try:
        export = read_npz(npz)
    except InputError as exc:
        log.warning("ignoring %s: %s", npz, exc)
        return None
    if export.source_sha256 != file_sha256(weights):
        log.warning("ignoring %s: exported from another version of %s; regenerate it with "
                    "`python -m retarget.network.numpy_weights %s`", npz, Path(weights).name, weights)  # fmt: skip
        return None
    return export


def main(argv: list[str] | None = None) -> int:
    """``python -m retarget.network.numpy_weights [WEIGHTS] [--out OUT]``."""

    parser = argparse.ArgumentParser(prog="python -m retarget.network.numpy_weights", description=__doc__.splitlines()[0])
    parser.add_argument("weights", nargs="?", type=Path, default=PACKAGED_WEIGHTS, help="checkpoint (default: packaged)")
    parser.add_argument("--out", type=Path, default=None, help="output .npz (default: beside the checkpoint)")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    try:
        export_npz(args.weights, args.out)
    except InputError as exc:
        parser.exit(2, f"error: {exc}\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
