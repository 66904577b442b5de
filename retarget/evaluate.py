"""Evaluation of retargeting on the motion world's test split (unseen motions, unseen characters).

A test case takes the motion of window ``mA`` performed by character ``cA`` seen from view ``vA`` and moves it
onto character ``cB`` seen from view ``vB``. The ground truth is the world's own answer: the same motion
replayed in 3D on ``cB``'s skeleton and projected by ``vB``'s camera. Every method learns about the reference
only from a *different* window (another motion) of ``cB`` seen from ``vB``, as a user's reference video would
show it: the network takes its skeleton and view codes and its placement from it, the baselines their scales.

The error is the paper's: the mean over frames, joints and both coordinates of the squared difference between
corresponding joints, with coordinates divided by the target's height (its skeleton's height in metres times
the camera's pixels per metre). It is shown x 10^3. RMSE in % of height and PCK at 5 % and 10 % of height are
its scale-free companions. Each is given as placed (the output as it lands in the reference's frame) and
root-aligned (each frame's MidHip subtracted from both), which isolates the pose from where it stands.
"""

from __future__ import annotations

import json
import logging
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Callable, Mapping, Sequence

import numpy as np
import torch

from pose_io.atomic import atomic_dir
from pose_io.track import PoseTrack
from retarget.baselines import global_scale_retarget, limb_scale_retarget
from retarget.preprocess import LAYOUT, ROOT_INDEX, body15_track, joints_to_channels

log = logging.getLogger(__name__)

Method = Callable[[PoseTrack, PoseTrack], PoseTrack]
METRICS = ("mse_x1e3", "rmse_pct", "pck_0.05", "pck_0.1")


@dataclass(frozen=True)
class EvalConfig:
    """Attributes: pairs (test cases), length (frames per case), seed, code_samples (per label for the
    silhouettes: motions x characters x views = code_samples^3 windows)."""

    pairs: int = 300
    length: int = 64
    seed: int = 0
    code_samples: int = 6


@dataclass(frozen=True)
class Case:
    motion: int
    source_character: int
    source_view: int
    character: int
    view: int
    reference_motion: int


def pose_errors(pred: np.ndarray, truth: np.ndarray, height: float) -> dict[str, float]:
    """The paper's error and its companions for one case.

    Args:
        pred: [T, J, 2] predicted pixels.
        truth: [T, J, 2] true pixels.
        height: the target's height in pixels.

    Returns:
        ``mse_x1e3`` (mean squared height-normalised coordinate error x 1000), ``rmse_pct`` (root mean squared
        joint distance in % of height), ``pck_0.05`` and ``pck_0.1`` (share of joints within that share of the
        height).
    """
    e = (np.asarray(pred, np.float64) - np.asarray(truth, np.float64)) / height  # [T, J, 2]
    dist = np.linalg.norm(e, axis=-1)  # [T, J]
    return {
        "mse_x1e3": float(np.mean(e**2) * 1e3),
        "rmse_pct": float(np.sqrt(np.mean(dist**2)) * 100),
        "pck_0.05": float(np.mean(dist < 0.05)),
        "pck_0.1": float(np.mean(dist < 0.1)),
    }


def root_aligned(joints: np.ndarray) -> np.ndarray:
    """[T, 15, 2] body15 -> the same with each frame's MidHip at the origin."""
    return joints - joints[:, ROOT_INDEX : ROOT_INDEX + 1]


def silhouette(features: np.ndarray, labels: np.ndarray) -> float:
    """Mean silhouette coefficient of ``features`` [N, D] clustered by ``labels`` [N] (Euclidean).

    For each sample, ``a`` is its mean distance to the rest of its cluster and ``b`` the smallest mean distance
    to another cluster; its coefficient is ``(b - a) / max(a, b)`` (0 for a cluster of one).
    """
    from scipy.spatial.distance import cdist

    labels = np.asarray(labels)
    names = np.unique(labels)
    if len(names) < 2:
        raise ValueError("silhouette needs at least two labels")
    d = cdist(features, features)  # [N, N]
    member = labels[None, :] == names[:, None]  # [K, N]
    sums = member.astype(np.float64) @ d  # [K, N] distance of each sample to all members of each cluster
    counts = member.sum(axis=1)  # [K]
    own = np.searchsorted(names, labels)  # [N]
    n = len(labels)
    own_count = counts[own]
    a = np.where(own_count > 1, sums[own, np.arange(n)] / np.maximum(own_count - 1, 1), 0.0)
    other = sums / counts[:, None]
    other[own, np.arange(n)] = np.inf
    b = other.min(axis=0)
    s = np.where(own_count > 1, (b - a) / np.maximum(np.maximum(a, b), 1e-12), 0.0)
    return float(s.mean())


def sample_cases(split: object, count: int, length: int, rng: np.random.Generator) -> list[Case]:
    """``count`` cases with cA != cB, and a reference window of a different motion than the driven one."""
    long_enough = [m for m in range(split.num_motions) if split.window_labels[m].clip_frames
                   - split.window_labels[m].start >= length]  # fmt: skip
    if len(long_enough) < 2 or split.num_characters < 2:
        raise ValueError(f"{split.name}: too few windows or characters to evaluate")
    cases = []
    for _ in range(count):
        m, ref = rng.choice(long_enough, size=2, replace=False)
        ca, cb = rng.choice(split.num_characters, size=2, replace=False)
        va, vb = rng.integers(0, split.num_views, size=2)
        cases.append(Case(int(m), int(ca), int(va), int(cb), int(vb), int(ref)))
    return cases


def network_method(weights: str | Path, device: str = "cpu") -> tuple[Method, object]:
    """A retargeting method backed by a checkpoint (ours or the authors'), and its Retargeter."""
    from retarget.api import load_retargeter

    net = load_retargeter(weights, device=device)

    def run(motion: PoseTrack, reference: PoseTrack) -> PoseTrack:
        return net.retarget(motion, net.reference_codes(reference))

    return run, net


def evaluate(
    split: object,
    methods: Mapping[str, Method],
    config: EvalConfig = EvalConfig(),
    fps: float = 30.0,
) -> dict[str, dict[str, dict[str, float]]]:
    """Mean errors of every method over the sampled cases of ``split``.

    Besides ``methods`` two 3D references that see the 3D truth are added: ``3D naive copy`` (the captured
    actor's own joints, unchanged, seen by the target's camera: the right view, the wrong body) and ``3D
    global scale`` (the same uniformly scaled to the target's height: the right view and size, the wrong
    proportions).

    Returns:
        method -> {"placed": {metric: mean}, "root_aligned": {metric: mean}}.
    """
    rng = np.random.default_rng(config.seed)
    cases = sample_cases(split, config.pairs, config.length, rng)
    size = tuple(split.canvas_size)
    scores: dict[str, dict[str, list[dict[str, float]]]] = {}

    def add(name: str, pred: np.ndarray, truth: np.ndarray, height: float) -> None:
        entry = scores.setdefault(name, {"placed": [], "root_aligned": []})
        entry["placed"].append(pose_errors(pred, truth, height))
        entry["root_aligned"].append(pose_errors(root_aligned(pred), root_aligned(truth), height))

    for case in cases:
        length = config.length
        source = split.window(case.motion, case.source_character, case.source_view, length)
        truth = split.window(case.motion, case.character, case.view, length)
        ref_len = min(length, split.window_labels[case.reference_motion].clip_frames
                      - split.window_labels[case.reference_motion].start)  # fmt: skip
        reference = split.window(case.reference_motion, case.character, case.view, ref_len)
        height = split.characters[case.character].height * split.camera(case.view).scale
        motion_track = body15_track(source, fps, size)
        reference_track = body15_track(reference, fps, size)
        for name, method in methods.items():
            add(name, method(motion_track, reference_track).joints, truth, height)
        actor = split.source_window3d(case.motion, length)  # [L, 18, 3]
        copy = split.project(actor[None], [case.view])[0]
        add("3D naive copy", copy, truth, height)
        actor_height = _actor_height(split)
        scaled = split.project((actor * (split.characters[case.character].height / actor_height))[None],
                               [case.view])[0]  # fmt: skip
        add("3D global scale", scaled, truth, height)

    return {
        name: {kind: {k: float(np.mean([s[k] for s in rows])) for k in METRICS} for kind, rows in entry.items()}
        for name, entry in scores.items()
    }


def _actor_height(split: object) -> float:
    """Height of the captured skeletons of ``split`` (median over its clips' first frames)."""
    from retarget.world.skeleton import skeleton_of, Motion3D

    cached = getattr(split, "_eval_actor_height", None)
    if cached is None:
        pos = np.asarray(split.source_positions[:: max(1, len(split.source_positions) // 2000)])
        cached = float(skeleton_of(Motion3D(pos.astype(np.float32), 30.0, "actors", "")).height)
        split._eval_actor_height = cached
    return cached


def code_silhouettes(
    net: object, split: object, config: EvalConfig = EvalConfig(), plot_dir: Path | None = None
) -> dict[str, float]:
    """Mean silhouette coefficients of motion, body and view codes (labels: motion, character, view).

    Uses ``code_samples`` motions x characters x views windows of the split; with ``plot_dir`` also writes a
    2D PCA scatter of each code as PNG.
    """
    rng = np.random.default_rng(config.seed + 1)
    k = config.code_samples
    motions = rng.choice(split.num_motions, size=min(k, split.num_motions), replace=False)
    chars = rng.choice(split.num_characters, size=min(k, split.num_characters), replace=False)
    views = np.linspace(0, split.num_views - 1, min(k, split.num_views)).round().astype(int)
    grid = np.array([(m, c, v) for m in motions for c in chars for v in views])  # [N, 3]
    joints = split.windows(grid[:, 0], grid[:, 1], grid[:, 2], config.length)  # [N, L, 15, 2]
    scale = net.preprocess.canvas_height / split.canvas_size[1]
    model = net.model
    with torch.inference_mode():
        x = joints_to_channels(torch.from_numpy(joints * scale).to(net.device), net.stats)  # [N, 30, L]
        codes = {"motion": model.encode_motion(x).flatten(1)}
        if getattr(model, "body_encoder", None) is not None:
            codes["body"] = model.encode_body(x).flatten(1)
        if getattr(model, "view_encoder", None) is not None:
            codes["view"] = model.encode_view(x).flatten(1)
    labels = {"motion": grid[:, 0], "body": grid[:, 1], "view": grid[:, 2]}
    result = {name: silhouette(c.cpu().numpy(), labels[name]) for name, c in codes.items()}
    if plot_dir is not None:
        _plot_codes(plot_dir, {n: c.cpu().numpy() for n, c in codes.items()}, labels, result)
    return result


def _plot_codes(folder: Path, codes: dict[str, np.ndarray], labels: dict[str, np.ndarray],
                scores: dict[str, float]) -> None:  # fmt: skip
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    for name, feats in codes.items():
        centred = feats - feats.mean(axis=0)
        _, _, vt = np.linalg.svd(centred, full_matrices=False)
        xy = centred @ vt[:2].T  # [N, 2] first two principal components
        fig, ax = plt.subplots(figsize=(4.5, 4.0), dpi=110)
        ax.scatter(xy[:, 0], xy[:, 1], c=labels[name], cmap="tab10", s=14)
        label = {"motion": "motion", "body": "character", "view": "view"}[name]
        ax.set_title(f"{name} codes, coloured by {label} (silhouette {scores[name]:.2f})", fontsize=9)
        ax.set_xticks([])
        ax.set_yticks([])
        fig.tight_layout()
        fig.savefig(folder / f"codes_{name}.png")
        plt.close(fig)


def markdown_table(results: Mapping[str, Mapping[str, Mapping[str, float]]], notes: Sequence[str]) -> str:
    """Method rows, placed and root-aligned metric columns."""
    head = ("| method | MSE x10³ | RMSE % | PCK@.05 | PCK@.1 | MSE x10³ (root-aligned) | RMSE % (r-a) | "
            "PCK@.05 (r-a) | PCK@.1 (r-a) |")  # fmt: skip
    lines = [head, "|---" * 9 + "|"]
    for name, r in results.items():
        cells = [f"{r[k]['mse_x1e3']:.2f} | {r[k]['rmse_pct']:.1f} | {r[k]['pck_0.05']:.3f} | {r[k]['pck_0.1']:.3f}"
                 for k in ("placed", "root_aligned")]  # fmt: skip
        lines.append(f"| {name} | {cells[0]} | {cells[1]} |")
    return "\n".join(lines + [""] + [f"- {n}" for n in notes]) + "\n"


def run_eval(
    split: object,
    out: Path,
    weights: str | Path | None,
    compare: Mapping[str, str | Path] | None = None,
    official: str | Path | None = None,
    config: EvalConfig = EvalConfig(),
    overwrite: bool = False,
    device: str = "cpu",
) -> tuple[dict, str]:
    """Evaluate every method, write ``eval.json``, ``eval.md`` and code plots into ``out`` (atomically)."""
    start = time.perf_counter()
    methods: dict[str, Method] = {}
    ours, net = network_method(weights, device)  # weights None -> the shipped ones
    methods["ours (full)"] = ours
    for name, path in (compare or {}).items():
        methods[name] = network_method(path, device)[0]
    if official is not None:
        methods["authors' released model"] = network_method(Path(official) / "pretrained_full.pth", device)[0]
    methods["global scaling (Everybody Dance Now)"] = global_scale_retarget
    methods["naive 2D FK (per-limb scaling)"] = limb_scale_retarget
    results = evaluate(split, methods, config)
    notes = [
        f"{config.pairs} cases of {config.length} frames from the `{split.name}` split (motions and characters "
        f"unseen in training), seed {config.seed}; the reference is another motion of the target character "
        "seen from the target view.",
        "MSE: the paper's error, mean squared joint-coordinate difference with coordinates divided by the "
        "target's height, x 10³. RMSE: root mean squared joint distance in % of height. PCK@a: share of joints "
        "within a x height. Root-aligned (r-a): each frame's MidHip subtracted from prediction and truth.",
        "3D naive copy: the captured actor's 3D joints, unretargeted, projected by the target camera (sees the "
        "true view). 3D global scale: the same uniformly scaled to the target's height. Both see 3D truth.",
    ]
    with atomic_dir(out, overwrite=overwrite) as tmp:
        silhouettes = code_silhouettes(net, split, config, plot_dir=tmp)
        notes.append("Mean silhouette coefficients of our codes (labels motion / character / view): "
                     + ", ".join(f"{k} {v:.3f}" for k, v in silhouettes.items()))  # fmt: skip
        table = markdown_table(results, notes)
        doc = {"config": asdict(config), "split": split.name, "results": results, "silhouettes": silhouettes,
               "weights": str(weights) if weights else "shipped", "seconds": time.perf_counter() - start}  # fmt: skip
        (tmp / "eval.json").write_text(json.dumps(doc, indent=2))
        (tmp / "eval.md").write_text(table)
    return doc, table
