"""How well a network's codes cluster by what they should encode: silhouettes and their PCA plots."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np
import torch

from pose_io.errors import InputError
from retarget.evaluate.config import DEFAULT_CONFIG, EvalConfig
from retarget.inference.tracks import body15_track, prepare_track
from retarget.network.preprocess import joints_to_channels
from retarget.world.split import WorldSplit

_LABEL_NAMES = {"motion": "motion", "body": "character", "view": "view"}


def silhouette(features: np.ndarray, labels: np.ndarray) -> float:
    """Mean silhouette coefficient of ``features`` [N, D] clustered by ``labels`` [N] (Euclidean).

    For each sample, ``a`` is its mean distance to the rest of its cluster and ``b`` the smallest mean distance
    to the members of another cluster; its coefficient is ``(b - a) / max(a, b)`` (0 for a cluster of one).
    About 1: tight, well separated clusters; about 0: the labels do not explain the layout.
    """
    from scipy.spatial.distance import cdist

    labels = np.asarray(labels)
    names = np.unique(labels)
    if len(names) < 2:
        raise ValueError("silhouette needs at least two labels")
    d = cdist(features, features)  # [N, N]
    member = labels[None, :] == names[:, None]  # [K, N]
    sums = member.astype(np.float64) @ d  # [K, N] summed distance of each sample to each cluster's members
    counts = member.sum(axis=1)  # [K]
    own = np.searchsorted(names, labels)  # [N]
    n = np.arange(len(labels))
    own_count = counts[own]
    a = sums[own, n] / np.maximum(own_count - 1, 1)
    other = sums / counts[:, None]
    other[own, n] = np.inf
    b = other.min(axis=0)
    s = np.where(own_count > 1, (b - a) / np.maximum(np.maximum(a, b), 1e-12), 0.0)
    return float(s.mean())


def mean_and_error(values: list[float]) -> tuple[float, float]:
    """Mean of per-grid silhouettes and its standard error (0 with one grid)."""
    v = np.asarray(values, dtype=np.float64)
    return float(v.mean()), float(v.std(ddof=1) / np.sqrt(len(v))) if len(v) > 1 else 0.0


def pca_2d(features: np.ndarray) -> np.ndarray:
    """[N, D] -> [N, 2] coordinates along the first two principal components."""
    x = torch.as_tensor(np.asarray(features, np.float64))
    centred = x - x.mean(dim=0)
    # Eigenvectors of the [N, N] Gram matrix (N << D here). torch rather than numpy: numpy's BLAS ignores
    # the thread count the command set and is many times slower on a busy machine.
    values, vectors = torch.linalg.eigh(centred @ centred.T)  # ascending
    top = values.flip(0)[:2].clamp(min=0.0)
    return (vectors.flip(1)[:, :2] * top.sqrt()).numpy()


def code_grid(split: WorldSplit, config: EvalConfig, grid: int = 0) -> np.ndarray:
    """[N, 3] (window, character, view) rows of silhouette grid ``grid``: ``code_samples`` distinct motion groups
    x characters x views.

    Raises:
        InputError: fewer than two windows, characters or views to cross.
    """
    rng = np.random.default_rng([config.seed, 1] if grid == 0 else [config.seed, 1, grid])
    by_group: dict[str, list[int]] = {}
    for m, lab in enumerate(split.window_labels):
        if lab.clip_frames - lab.start >= split.window_length:
            by_group.setdefault(lab.group, []).append(m)
    groups = sorted(by_group)
    k = config.code_samples
    if len(groups) >= 2:
        chosen = rng.choice(len(groups), size=min(k, len(groups)), replace=False)
        motions = [int(rng.choice(by_group[groups[g]])) for g in chosen]
    else:  # one motion group: distinct windows of it
        pool = by_group[groups[0]] if groups else []
        motions = [int(m) for m in rng.choice(pool, size=min(k, len(pool)), replace=False)]
    chars = rng.choice(split.num_characters, size=min(k, split.num_characters), replace=False)
    views = np.unique(np.linspace(0, split.num_views - 1, min(k, split.num_views)).round().astype(int))
    if min(len(motions), len(chars), len(views)) < 2:
        raise InputError(f"{split.name} split: too few windows or characters for code silhouettes")
    return np.array([(m, c, v) for m in motions for c in chars for v in views])


def grid_inputs(net: object, split: WorldSplit, grid: np.ndarray, fps: float) -> torch.Tensor:
    """[N, 30, L] network inputs of the windows of ``grid`` [N, 3] (window, character, view; pitch 0), prepared
    with ``net``'s preprocessing and statistics, on ``net``'s device."""
    windows = split.windows(grid[:, 0], grid[:, 1], grid[:, 2])  # [N, L, 15, 2]
    size = tuple(split.canvas_size)
    canvas = np.stack([prepare_track(body15_track(w, fps, size), net.preprocess) for w in windows])  # [N, L, 15, 2]
    return joints_to_channels(torch.from_numpy(canvas), net.stats).to(net.device, torch.float32)


def _grid_codes(net: object, split: WorldSplit, grid: np.ndarray, fps: float) -> dict[str, np.ndarray]:
    """Name -> [N, D] codes of a grid's windows, for the names among "motion", "body", "view" the network has."""
    x = grid_inputs(net, split, grid, fps)  # [N, 30, L]
    model = net.model
    encoders = {"motion": model.encode_motion}
    if model.body_encoder is not None:
        encoders["body"] = model.encode_body
    if model.view_encoder is not None:
        encoders["view"] = model.encode_view
    with torch.inference_mode():
        return {name: torch.cat([enc(chunk).flatten(1) for chunk in x.split(64)]).double().cpu().numpy()
                for name, enc in encoders.items()}  # fmt: skip


def code_silhouettes(
    net: object, split: WorldSplit, config: EvalConfig = DEFAULT_CONFIG, fps: float = 30.0
) -> tuple[dict[str, float], dict[str, float], dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Mean silhouette coefficients of a network's codes over ``code_grids`` grids of the split's windows.

    Each grid crosses ``code_samples`` windows of distinct motion groups, characters and views (pitch 0); motion
    codes are labelled by motion, skeleton codes by character, view codes by view.

    Args:
        net: a ``Retargeter``.
        split: the windows.
        config: ``code_samples``, ``code_grids`` and ``seed``.
        fps: frame rate of the world.

    Returns:
        ``(scores, errors, codes, labels)``: name -> mean silhouette over the grids, name -> its standard error
        (0 with one grid), name -> [N, D] codes of grid 0, name -> [N] their labels, for the names among
        "motion", "body", "view" the network has.
    """
    per_grid: list[dict[str, float]] = []
    for g in range(config.code_grids):
        grid = code_grid(split, config, g)  # [N, 3]
        codes = _grid_codes(net, split, grid, fps)
        all_labels = {"motion": grid[:, 0], "body": grid[:, 1], "view": grid[:, 2]}
        labels = {name: all_labels[name] for name in codes}
        per_grid.append({name: silhouette(c, labels[name]) for name, c in codes.items()})
        if g == 0:
            first = codes, labels
    summary = {name: mean_and_error([s[name] for s in per_grid]) for name in per_grid[0]}
    scores = {name: mean for name, (mean, _) in summary.items()}
    errors = {name: error for name, (_, error) in summary.items()}
    return scores, errors, *first


def plot_codes(
    path: Path, title: str, codes: Mapping[str, np.ndarray], labels: Mapping[str, np.ndarray],
    scores: Mapping[str, float],
) -> None:  # fmt: skip
    """One PNG with a 2D PCA scatter per code, coloured by its label.

    Draws on a bare ``Figure`` (no pyplot, no backend change), so the caller's matplotlib state is untouched.

    Args:
        path: the PNG to write.
        title: what the codes are of (a network's row name).
        codes: name -> [N, D] codes (see :func:`code_silhouettes`).
        labels: name -> [N] labels of the same samples.
        scores: name -> silhouette coefficient, shown in each panel's title.
    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=(4.2 * len(codes), 4.0), dpi=100)
    axes = fig.subplots(1, len(codes), squeeze=False)
    for ax, (name, feats) in zip(axes[0], codes.items()):
        xy = pca_2d(feats)
        _, colour = np.unique(labels[name], return_inverse=True)
        ax.scatter(xy[:, 0], xy[:, 1], c=colour, cmap="tab10", s=12, vmin=0, vmax=9)
        ax.set_title(f"{name} codes by {_LABEL_NAMES[name]}\nsilhouette {scores[name]:.2f}", fontsize=9)
        ax.set_xticks([])
        ax.set_yticks([])
    fig.suptitle(f"{title}: first two principal components", fontsize=10)
    fig.tight_layout()
    fig.savefig(path)
