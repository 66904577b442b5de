"""The search index: every track's feature sequence in one contiguous array, built once, stored as one file.

File layout (``.npz`` written with :func:`numpy.savez` into an atomic temporary file, read back with
``allow_pickle=False``)::

    format      "clone2d-search-index"
    version     int, FORMAT_VERSION when written
    kind        "motion" (the network's motion codes) | "joints" (the raw-joint baseline)
    digest      identity of the encoder (:func:`retarget.applications.search.features.model_digest`)
    stride      frames (at ``fps``) per feature step
    fps         frame rate tracks were resampled to before encoding
    features    [C, N] float16, every track's sequence one after the other, minus ``center``
    center      [C] float32, the mean feature step of the index (subtracted from queries too)
    offsets     [M + 1] int64, track m holds steps offsets[m] .. offsets[m + 1] - 1
    paths       [M] str, where each track was read from
    track_fps   [M] float64, each track's own frame rate
    frames      [M] int64, each track's own frame count
"""

from __future__ import annotations

import logging
import os
import zipfile
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch

from pose_io.atomic import atomic_file
from pose_io.errors import InputError
from pose_io.folders import find_tracks
from pose_io.track import PoseTrack
from retarget.applications.search.features import TrackEncoder, track_features

log = logging.getLogger(__name__)

FORMAT = "clone2d-search-index"
FORMAT_VERSION = 1


@dataclass(frozen=True, eq=False)
class SearchIndex:
    """Feature sequences of many tracks, concatenated, ready to be searched.

    Attributes:
        features: [C, N] float32 tensor, centred (``center`` subtracted).
        center: [C] float32 tensor.
        offsets: [M + 1] int64 array of step offsets per track.
        paths: [M] track paths.
        track_fps: [M] float64 own frame rates.
        frames: [M] int64 own frame counts.
        kind, digest, stride, fps: the encoder that made ``features`` (see :class:`TrackEncoder`).
        track_of_step: [N] int64 tensor, the track of every step (derived).
        step_cumsum: [N + 1] float64 tensor, running sum of squared step norms (derived: window norms).
    """

    features: torch.Tensor
    center: torch.Tensor
    offsets: np.ndarray
    paths: tuple[str, ...]
    track_fps: np.ndarray
    frames: np.ndarray
    kind: str
    digest: str
    stride: int
    fps: float
    track_of_step: torch.Tensor = field(init=False, repr=False)
    step_cumsum: torch.Tensor = field(init=False, repr=False)

    def __post_init__(self) -> None:
        m = len(self.paths)
        offsets = np.asarray(self.offsets, dtype=np.int64)
        if (
            self.features.ndim != 2
            or self.center.shape != (self.features.shape[0],)
            or offsets.shape != (m + 1,)
            or np.asarray(self.track_fps).shape != (m,)
            or np.asarray(self.frames).shape != (m,)
            or (m and (offsets[0] != 0 or offsets[-1] != self.features.shape[1] or (np.diff(offsets) <= 0).any()))
        ):
            raise InputError("search index: inconsistent array shapes or offsets")
        if self.stride < 1 or not self.fps > 0:
            raise InputError("search index: invalid stride or frame rate")
        lengths = torch.from_numpy(np.diff(offsets))
        object.__setattr__(self, "offsets", offsets)
        object.__setattr__(self, "track_of_step", torch.repeat_interleave(torch.arange(m), lengths))
        squares = self.features.double().square().sum(dim=0)  # [N]
        object.__setattr__(self, "step_cumsum", torch.cat([squares.new_zeros(1), squares.cumsum(0)]))

    @property
    def num_tracks(self) -> int:
        return len(self.paths)

    @property
    def num_steps(self) -> int:
        return int(self.features.shape[1])

    @property
    def num_frames(self) -> int:
        """Total frames of the indexed tracks (their own frame counts)."""
        return int(np.sum(self.frames))

    def track_features(self, track: int) -> torch.Tensor:
        """[C, steps] centred features of one track."""
        return self.features[:, self.offsets[track] : self.offsets[track + 1]]


def from_sequences(
    sequences: Sequence[np.ndarray],
    paths: Sequence[str],
    track_fps: Sequence[float],
    frames: Sequence[int],
    encoder: TrackEncoder,
) -> SearchIndex:
    """An index from per-track feature sequences ``[C, T_m]`` (e.g. from :func:`track_features`).

    The features are centred on their mean step: motion codes come out of a leaky ReLU and share a large
    common component, which would make every cosine close to 1.
    """
    if not sequences:
        raise InputError("search index: no tracks to index")
    features = torch.from_numpy(np.concatenate(sequences, axis=1).astype(np.float32))  # [C, N]
    center = features.mean(dim=1)
    offsets = np.concatenate([[0], np.cumsum([s.shape[1] for s in sequences])]).astype(np.int64)
    return SearchIndex(
        features - center[:, None], center, offsets, tuple(map(str, paths)), np.asarray(track_fps, np.float64),
        np.asarray(frames, np.int64), encoder.kind, encoder.digest, encoder.stride, encoder.fps,
    )


@dataclass(frozen=True)
class Skipped:
    """A file a folder walk found but could not index."""

    path: str
    reason: str


def build_index(
    inputs: Iterable[str | os.PathLike],
    encoder: TrackEncoder,
    read: Callable[[Path], PoseTrack] | None = None,
    progress: Callable[[int, int, str], None] | None = None,
) -> tuple[SearchIndex, list[Skipped]]:
    """Encode every track once and gather the features.

    Args:
        inputs: files and folders, searched recursively (:func:`pose_io.folders.find_tracks`).
        encoder: a :class:`~retarget.applications.search.features.TrackEncoder`.
        read: reads one track (default :func:`pose_io.readers.read_track`).
        progress: called as ``progress(done, total, path)``.

    Returns:
        (index, tracks found in folders but skipped, with why).

    Raises:
        InputError: a named track that cannot be read or encoded, or nothing to index.
    """
    if read is None:
        from pose_io.readers import read_track as read
    found = [(f.path, f.named) for f in find_tracks(inputs, recursive=True)]
    sequences, paths, fps, frames, skipped = [], [], [], [], []
    for k, (path, named) in enumerate(found):
        if progress is not None:
            progress(k, len(found), str(path))
        try:
            track = read(path)
            sequences.append(track_features(encoder, track, str(path)))
        except InputError as exc:
            if named:
                raise
            log.warning("skipping %s", exc)
            skipped.append(Skipped(str(path), str(exc)))
            continue
        paths.append(str(path))
        fps.append(track.fps)
        frames.append(len(track))
    if progress is not None:
        progress(len(found), len(found), "")
    if not sequences:
        raise InputError(f"no readable pose tracks among {len(found)} found ({len(skipped)} skipped)")
    return from_sequences(sequences, paths, fps, frames, encoder), skipped


def save_index(index: SearchIndex, path: str | os.PathLike, overwrite: bool = False) -> Path:
    """Write ``index`` as one ``.npz`` file, atomically (features stored as float16)."""
    path = Path(path)
    with atomic_file(path, overwrite=overwrite) as tmp, open(tmp, "wb") as f:
        np.savez(
            f,
            format=np.array(FORMAT),
            version=np.array(FORMAT_VERSION, dtype=np.int64),
            kind=np.array(index.kind),
            digest=np.array(index.digest),
            stride=np.array(index.stride, dtype=np.int64),
            fps=np.array(index.fps, dtype=np.float64),
            features=index.features.numpy().astype(np.float16),
            center=index.center.numpy().astype(np.float32),
            offsets=index.offsets,
            paths=np.array(index.paths, dtype=np.str_).reshape(-1),
            track_fps=index.track_fps,
            frames=index.frames,
        )
    return path


def load_index(path: str | os.PathLike) -> SearchIndex:
    """Read an index written by :func:`save_index`.

    Raises:
        InputError: a missing, corrupt or foreign file, or one of a newer format version.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: no such search index")
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {k: data[k] for k in data.files}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
        raise InputError(f"{path}: not a readable search index ({exc})") from None
    if str(arrays.get("format", "")) != FORMAT:
        raise InputError(f"{path}: not a clone2d search index")
    version = int(arrays.get("version", -1))
    if version > FORMAT_VERSION:
        raise InputError(
            f"{path}: search index of format version {version}; this clone2d reads up to {FORMAT_VERSION}"
            " (upgrade clone2d or rebuild the index)"
        )
    if version < 1:
        raise InputError(f"{path}: search index of unknown format version {version}")
    try:
        features = torch.from_numpy(np.asarray(arrays["features"], dtype=np.float32))
        if not torch.isfinite(features).all():
            raise ValueError("non-finite features")
        return SearchIndex(
            features,
            torch.from_numpy(np.asarray(arrays["center"], dtype=np.float32)),
            np.asarray(arrays["offsets"], dtype=np.int64),
            tuple(str(p) for p in np.asarray(arrays["paths"]).reshape(-1)),
            np.asarray(arrays["track_fps"], dtype=np.float64),
            np.asarray(arrays["frames"], dtype=np.int64),
            str(arrays["kind"]),
            str(arrays["digest"]),
            int(arrays["stride"]),
            float(arrays["fps"]),
        )
    except (KeyError, ValueError, TypeError) as exc:
        raise InputError(f"{path}: damaged search index ({exc})") from None
