"""Evaluation of 2D retargeting on the motion world: the error table and the code silhouettes.

Protocol. A *case* moves the motion of window ``mA`` performed by character ``cA`` and seen by camera A onto
character ``cB`` seen by camera B (``cA != cB``; each camera is one of the 13 view bins with a pitch drawn
uniformly in +-``max_pitch`` degrees; every choice comes from one seeded generator). The ground truth is the
world's own answer: the same 3D motion replayed on ``cB`` (``retarget_3d``: every bone keeps its direction and
takes ``cB``'s length, the root path is scaled by the leg ratio, the feet stay on the ground) and projected
by camera B with the framing rule - ``WorldSplit.window(mA, cB, vB)``.

What a method learns about B comes only from a *reference*: another window of the split, performed by ``cB``
and seen by camera B, of another motion (another motion group when the split has one, else frames that do
not overlap the evaluated ones), as a user's reference video would show it. Networks take their skeleton and
view codes and their placement from it, the 2D baselines their scale statistics.

Sources of cases: the split's own windows (for ``test``: motions and characters never seen in training) and,
optionally, extra mocap clips replayed on the same characters (:class:`ClipMotions`), still with references
from the split.

Metrics (:func:`pose_errors`), with coordinates divided by the target's height ``h`` in pixels (the height of
``cB``'s skeleton times the camera's pixels per metre): the paper's error, the mean over frames, joints and
both coordinates of the squared difference, shown x 10^3 (units h^2 x 10^-3); RMSE, the root mean squared
joint distance of a case in % of ``h``; PCK@a, the share of joints within ``a h`` of the truth. Each is
reported three ways (:data:`ALIGNMENTS`): ``pose`` (each frame's MidHip subtracted from prediction and truth,
the 14 other joints scored: the paper's numbers are about the pose), ``with_root`` (one translation per case
removed, the least-squares one, so the root trajectory counts but not where in the frame the reference
stood) and ``placed`` (the output as it lands in the reference's frame).

Rows: the networks (ours, ``--compare`` checkpoints, the authors' released models), the 2D baselines of
:mod:`retarget.baselines`, and three 3D references that see the 3D truth (:data:`REFERENCES_3D`).
"""

from __future__ import annotations

import json
import logging
import re
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import torch

from pose_io.atomic import atomic_dir, check_new_output
from pose_io.errors import InputError
from pose_io.measures import amplitude_ratio, pose_error
from pose_io.track import PoseTrack
from retarget.baselines import global_scale_retarget, limb_scale_retarget
from retarget.preprocess import ROOT_INDEX, body15_track, joints_to_channels, prepare_track
from retarget.world.camera import MAX_PITCH
from retarget.world.dataset import WindowLabel, WorldSplit, window_starts
from retarget.world.skeleton import Motion3D, Skeleton, assemble, bone_vectors, joint_index, retarget_3d

log = logging.getLogger(__name__)

Method = Callable[[PoseTrack, PoseTrack], PoseTrack]  # (motion track, reference track) -> retargeted track
Progress = Callable[[int, int], None]

METRICS: tuple[str, ...] = ("mse_x1e3", "rmse_pct", "pck_0.05", "pck_0.1", "amplitude")
ALIGNMENTS: tuple[str, ...] = ("pose", "with_root", "placed")
_WORLD_ROOT = joint_index("mid_hip")

BASELINES: dict[str, Method] = {
    "global scaling (EDN)": global_scale_retarget,
    "2D per-limb scaling (FK)": limb_scale_retarget,
}
# The authors' release: row name -> file in the --official folder.
OFFICIAL_FILES: dict[str, str] = {
    "authors' full": "pretrained_full.pth",
    "authors' skeleton-only": "pretrained_skeleton.pth",
    "authors' view-only": "pretrained_view.pth",
}
REFERENCES_3D: dict[str, str] = {
    "3D naive copy": "A's 3D joints unchanged (A's body, not B's), projected by camera B: the error of not "
    "retargeting at all, with the view solved exactly",
    "3D global scale": "A's 3D joints scaled uniformly by height(B) / height(A) about the ground under the first "
    "root, projected by camera B: right view and height, A's proportions (EDN's global scaling with 3D truth)",
    "3D rotation copy": "the paper's 3D baseline with 3D truth: A's joint rotations (bone directions) on B's "
    "bone lengths, A's root path copied unscaled, projected by camera B; its pose is the truth's, so only the "
    "root path (stride length, feet off or through the ground) differs",
}
DESCRIPTIONS: dict[str, str] = {
    "ours": "our network; skeleton and view codes and placement from the reference window",
    "global scaling (EDN)": "Everybody Dance Now's global pose normalisation: per-frame scale and offset "
    "interpolated between the near and far ankle positions of the driver and of the reference",
    "2D per-limb scaling (FK)": "naive 2D retargeting: every 2D limb of the driver scaled to the reference's "
    "2D limb length (95th percentile over the window), rebuilt from MidHip by forward kinematics, root path "
    "scaled by the leg ratio",
    **{name: "the authors' released weights (" + file + ")" for name, file in OFFICIAL_FILES.items()},
    **REFERENCES_3D,
}


@dataclass(frozen=True)
class EvalConfig:
    """What is evaluated.

    Attributes:
        pairs: cases per source (the split, and the extra clips if any).
        length: frames of an evaluated case.
        reference_length: frames of a reference window.
        seed: seeds every choice of cases and of the silhouette windows.
        max_pitch: cameras get a pitch drawn uniformly in +-max_pitch degrees.
        code_samples: motions, characters and views each in the silhouette grid (``code_samples^3`` windows).
    """

    pairs: int = 500
    length: int = 64
    reference_length: int = 64
    seed: int = 0
    max_pitch: float = MAX_PITCH
    code_samples: int = 6

    def __post_init__(self) -> None:
        if self.pairs < 1 or self.length < 8 or self.reference_length < 8:
            raise ValueError("pairs must be >= 1 and length, reference_length >= 8")
        if self.code_samples < 2 or self.max_pitch < 0:
            raise ValueError("code_samples must be >= 2 and max_pitch >= 0")


@dataclass(frozen=True)
class Case:
    """One test case: motion window ``motion`` from character/camera A onto character/camera B."""

    motion: int
    source_character: int
    source_view: int
    source_pitch: float
    character: int
    view: int
    pitch: float
    reference: int  # window of the split that shows character B through camera B


# ---------------------------------------------------------------------------------------------------------
# Metrics.


def pose_errors(pred: np.ndarray, truth: np.ndarray, height: float) -> dict[str, float]:
    """The paper's error and its companions for one case.

    Args:
        pred: [T, J, 2] predicted pixels.
        truth: [T, J, 2] true pixels.
        height: the target's height in pixels.

    Returns:
        ``mse_x1e3``: mean over frames, joints and coordinates of the squared height-normalised difference,
        x 1000; ``rmse_pct``: root mean squared joint distance in % of the height; ``pck_0.05``, ``pck_0.1``:
        share of joints closer than that share of the height; ``amplitude``: the prediction's range of
        motion over the truth's (:func:`pose_io.measures.amplitude_ratio`; 1 = neither damped nor exaggerated).
    """
    scores = pose_error(pred, truth, height, (0.05, 0.1))
    return {
        "mse_x1e3": scores["mse"] * 1e3,
        "rmse_pct": scores["rmse_pct"],
        "pck_0.05": scores["pck_0.05"],
        "pck_0.1": scores["pck_0.1"],
        "amplitude": amplitude_ratio(pred, height, truth, height),
    }


def root_aligned(joints: np.ndarray) -> np.ndarray:
    """[T, 15, 2] body15 -> [T, 14, 2]: every other joint relative to the same frame's MidHip."""
    return np.delete(joints - joints[:, ROOT_INDEX : ROOT_INDEX + 1], ROOT_INDEX, axis=1)


def offset_aligned(pred: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """[T, J, 2] ``pred`` moved by the one translation that brings it closest to ``truth`` (least squares)."""
    return pred + (truth - pred).reshape(-1, 2).mean(axis=0)


def case_scores(pred: np.ndarray, truth: np.ndarray, height: float) -> dict[str, dict[str, float]]:
    """:func:`pose_errors` of [T, 15, 2] body15 ``pred`` vs ``truth`` under every alignment of :data:`ALIGNMENTS`."""
    return {
        "pose": pose_errors(root_aligned(pred), root_aligned(truth), height),
        "with_root": pose_errors(offset_aligned(pred, truth), truth, height),
        "placed": pose_errors(pred, truth, height),
    }


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


def pca_2d(features: np.ndarray) -> np.ndarray:
    """[N, D] -> [N, 2] coordinates along the first two principal components."""
    x = torch.as_tensor(np.asarray(features, np.float64))
    centred = x - x.mean(dim=0)
    # Eigenvectors of the [N, N] Gram matrix (N << D here). torch rather than numpy: numpy's BLAS ignores
    # the thread count the command set and is many times slower on a busy machine.
    values, vectors = torch.linalg.eigh(centred @ centred.T)  # ascending
    top = values.flip(0)[:2].clamp(min=0.0)
    return (vectors.flip(1)[:, :2] * top.sqrt()).numpy()


# ---------------------------------------------------------------------------------------------------------
# 3D references: what a 3D pipeline that knows the true 3D motion and camera would output.


def naive_copy_3d(pos_a: np.ndarray, skel_a: Skeleton, skel_b: Skeleton) -> np.ndarray:
    """[T, 18, 3] A's joints unchanged (see :data:`REFERENCES_3D`)."""
    return pos_a.copy()


def global_scale_3d(pos_a: np.ndarray, skel_a: Skeleton, skel_b: Skeleton) -> np.ndarray:
    """[T, 18, 3] A's joints scaled by the height ratio about the world origin (ground under the first root)."""
    return pos_a * np.float32(skel_b.height / skel_a.height)


def rotation_copy_3d(pos_a: np.ndarray, skel_a: Skeleton, skel_b: Skeleton) -> np.ndarray:
    """[T, 18, 3] A's bone directions with B's bone lengths on A's root path."""
    vectors = bone_vectors(pos_a.astype(np.float64)) * (skel_b.array / skel_a.array)[:, None]  # [T, 17, 3]
    return assemble(pos_a[:, _WORLD_ROOT].astype(np.float64), vectors).astype(np.float32)


_REFERENCE_FUNCTIONS: dict[str, Callable[[np.ndarray, Skeleton, Skeleton], np.ndarray]] = {
    "3D naive copy": naive_copy_3d,
    "3D global scale": global_scale_3d,
    "3D rotation copy": rotation_copy_3d,
}


# ---------------------------------------------------------------------------------------------------------
# Cases.


class ClipMotions:
    """Extra mocap clips replayed on a split's characters, cut into windows like the world's.

    Offers what evaluation reads of a ``WorldSplit`` as a source of motions: ``num_motions``,
    ``window_labels`` and ``window3d``.

    Args:
        motions: the clips (``load_motion``), each at least ``window`` frames long.
        characters: the characters to replay them on (those of the split).
        window: window length in frames.
        stride: step between window starts.
    """

    def __init__(self, motions: Sequence[Motion3D], characters: Sequence[Skeleton], window: int, stride: int) -> None:
        short = [m.source or m.name for m in motions if m.num_frames < window]
        if short:
            raise InputError(f"{short[0]}: shorter than the {window} evaluated frames")
        # [clip][character] -> [F, 18, 3] replay
        self._replays = [[retarget_3d(m, c).positions for c in characters] for m in motions]
        labels, index = [], []
        for k, m in enumerate(motions):
            for start in window_starts(m.num_frames, window, stride):
                labels.append(WindowLabel(m.name, m.source, start, f"extra:{m.source or m.name}", m.num_frames))
                index.append((k, start))
        self.window_labels: tuple[WindowLabel, ...] = tuple(labels)
        self._index = index
        self.window_length = window

    @property
    def num_motions(self) -> int:
        return len(self._index)

    def window3d(self, motion: int, character: int, length: int | None = None, offset: int = 0) -> np.ndarray:
        """[length, 18, 3] like ``WorldSplit.window3d``: metres, first root over the origin, ground y = 0."""
        clip, start = self._index[motion]
        first = start + offset
        pos = np.array(self._replays[clip][character][first : first + (length or self.window_length)])
        pos[..., 0] -= pos[0, _WORLD_ROOT, 0]
        pos[..., 2] -= pos[0, _WORLD_ROOT, 2]
        return pos


def _overlaps(a: WindowLabel, a_len: int, b: WindowLabel, b_len: int) -> bool:
    return a.path == b.path and a.start < b.start + b_len and b.start < a.start + a_len


def sample_cases(
    motions: WorldSplit | ClipMotions, split: WorldSplit, config: EvalConfig, rng: np.random.Generator
) -> list[Case]:
    """``config.pairs`` cases of ``motions`` with references from ``split`` (see the module docstring).

    Raises:
        InputError: no window long enough, fewer than two characters, or no reference window that shares no
            frame with a case.
    """
    labels, refs_all = motions.window_labels, split.window_labels
    refs = [r for r, lab in enumerate(refs_all) if lab.clip_frames - lab.start >= config.reference_length]
    if split.num_characters < 2:
        raise InputError(f"{split.name} split: retargeting needs at least two characters")
    candidates: dict[int, list[int]] = {}  # evaluated window -> its possible reference windows
    for m, lab in enumerate(labels):
        if lab.clip_frames - lab.start < config.length:
            continue
        other = [r for r in refs if refs_all[r].group != lab.group]
        if not other:  # a one-motion split: any window that shares no frame with the case
            other = [r for r in refs if not _overlaps(lab, config.length, refs_all[r], config.reference_length)]
        if other:
            candidates[m] = other
    if not candidates:
        raise InputError(f"{split.name} split: no {config.length}-frame window with a reference window of "
                         f"{config.reference_length} frames that shares none of its frames")  # fmt: skip
    fits = sorted(candidates)
    cases = []
    for _ in range(config.pairs):
        m = fits[rng.integers(len(fits))]
        ca, cb = rng.choice(split.num_characters, size=2, replace=False)
        va, vb = rng.integers(0, split.num_views, size=2)
        pa, pb = rng.uniform(-config.max_pitch, config.max_pitch, size=2)
        ref = candidates[m][rng.integers(len(candidates[m]))]
        cases.append(Case(m, int(ca), int(va), float(pa), int(cb), int(vb), float(pb), ref))
    return cases


# ---------------------------------------------------------------------------------------------------------
# Running the methods.


def network_method(weights: str | Path, device: str = "cpu") -> tuple[Method, object]:
    """A retargeting method backed by a checkpoint (ours or the authors'), and its ``Retargeter``."""
    from retarget.api import load_retargeter

    net = load_retargeter(weights, device=device)

    def run(motion: PoseTrack, reference: PoseTrack) -> PoseTrack:
        return net.retarget(motion, net.reference_codes(reference))

    return run, net


def _training_seed(path: Path) -> int | None:
    """The world seed a clone2d checkpoint was trained with, when it records one."""
    from retarget.checkpoint import load_weights

    training = load_weights(path).training or {}
    seed = training.get("config", {}).get("seed") if isinstance(training.get("config"), dict) else None
    return int(seed) if isinstance(seed, int) else None


def evaluate(
    split: WorldSplit,
    methods: Mapping[str, Method],
    config: EvalConfig = EvalConfig(),
    motions: ClipMotions | None = None,
    fps: float = 30.0,
    progress: Progress | None = None,
) -> dict[str, dict[str, dict[str, float]]]:
    """Mean scores of every method and of the 3D references over the sampled cases.

    Args:
        split: gives the characters, cameras and reference windows (and the motions unless ``motions``).
        methods: row name -> method; the 3D references of :data:`REFERENCES_3D` are added after them.
        config: cases and their lengths.
        motions: another source of motions (extra clips replayed on ``split``'s characters).
        fps: frame rate of the world (passed on with the tracks).
        progress: called as ``progress(done, total)`` after each case.

    Returns:
        row -> alignment -> ``{metric: mean over cases, metric + "_se": its standard error}``.
    """
    source = split if motions is None else motions
    cases = sample_cases(source, split, config, np.random.default_rng(config.seed))
    size = tuple(split.canvas_size)
    rows: dict[str, list[dict[str, dict[str, float]]]] = {name: [] for name in [*methods, *_REFERENCE_FUNCTIONS]}
    for k, case in enumerate(cases):
        skel_a, skel_b = split.characters[case.source_character], split.characters[case.character]
        pos_a = source.window3d(case.motion, case.source_character, config.length)  # [L, 18, 3]
        pos_b = source.window3d(case.motion, case.character, config.length)
        ref3d = split.window3d(case.reference, case.character, config.reference_length)
        motion2d = split.project(pos_a[None], [case.source_view], pitch_deg=[case.source_pitch])[0]  # [L, 15, 2]
        reference2d = split.project(ref3d[None], [case.view], pitch_deg=[case.pitch])[0]
        built = [f(pos_a, skel_a, skel_b) for f in _REFERENCE_FUNCTIONS.values()]
        seen = split.project(np.stack([pos_b, *built]), [case.view] * (1 + len(built)),
                             pitch_deg=[case.pitch] * (1 + len(built)))  # fmt: skip  # [1 + R, L, 15, 2]
        truth = seen[0]
        height = skel_b.height * split.camera(case.view).scale  # pixels
        motion_track = body15_track(motion2d, fps, size)
        reference_track = body15_track(reference2d, fps, size)
        for name, method in methods.items():
            rows[name].append(case_scores(method(motion_track, reference_track).joints, truth, height))
        for name, pred in zip(_REFERENCE_FUNCTIONS, seen[1:]):
            rows[name].append(case_scores(pred, truth, height))
        if progress is not None:
            progress(k + 1, len(cases))
    return {name: _summarise(scores) for name, scores in rows.items()}


def _summarise(scores: list[dict[str, dict[str, float]]]) -> dict[str, dict[str, float]]:
    out: dict[str, dict[str, float]] = {}
    for align in ALIGNMENTS:
        entry: dict[str, float] = {}
        for metric in METRICS:
            values = np.array([s[align][metric] for s in scores])
            entry[metric] = float(values.mean())
            entry[metric + "_se"] = float(values.std(ddof=1) / np.sqrt(len(values))) if len(values) > 1 else 0.0
        out[align] = entry
    return out


# ---------------------------------------------------------------------------------------------------------
# Codes.


def code_silhouettes(
    net: object, split: WorldSplit, config: EvalConfig = EvalConfig(), fps: float = 30.0
) -> tuple[dict[str, float], dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Mean silhouette coefficients of a network's codes on a grid of the split's windows.

    The grid crosses ``code_samples`` windows of distinct motion groups, characters and views (pitch 0); motion
    codes are labelled by motion, skeleton codes by character, view codes by view.

    Args:
        net: a ``Retargeter``.
        split: the windows.
        config: ``code_samples`` and ``seed``.
        fps: frame rate of the world.

    Returns:
        ``(scores, codes, labels)``: name -> silhouette, name -> [N, D] codes, name -> [N] labels, for the
        names among "motion", "body", "view" the network has.
    """
    rng = np.random.default_rng([config.seed, 1])
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
    grid = np.array([(m, c, v) for m in motions for c in chars for v in views])  # [N, 3]
    windows = split.windows(grid[:, 0], grid[:, 1], grid[:, 2])  # [N, L, 15, 2]
    size = tuple(split.canvas_size)
    canvas = np.stack([prepare_track(body15_track(w, fps, size), net.preprocess) for w in windows])  # [N, L, 15, 2]
    model = net.model
    x = joints_to_channels(torch.from_numpy(canvas), net.stats).to(net.device, torch.float32)  # [N, 30, L]
    encoders = {"motion": model.encode_motion}
    if model.body_encoder is not None:
        encoders["body"] = model.encode_body
    if model.view_encoder is not None:
        encoders["view"] = model.encode_view
    with torch.inference_mode():
        codes = {name: torch.cat([enc(chunk).flatten(1) for chunk in x.split(64)]).double().cpu().numpy()
                 for name, enc in encoders.items()}  # fmt: skip
    all_labels = {"motion": grid[:, 0], "body": grid[:, 1], "view": grid[:, 2]}
    labels = {name: all_labels[name] for name in codes}
    scores = {name: silhouette(c, labels[name]) for name, c in codes.items()}
    return scores, codes, labels


_LABEL_NAMES = {"motion": "motion", "body": "character", "view": "view"}


def plot_codes(
    path: Path, title: str, codes: Mapping[str, np.ndarray], labels: Mapping[str, np.ndarray],
    scores: Mapping[str, float],
) -> None:  # fmt: skip
    """One PNG with a 2D PCA scatter per code, coloured by its label."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(codes), figsize=(4.2 * len(codes), 4.0), dpi=100, squeeze=False)
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
    plt.close(fig)


# ---------------------------------------------------------------------------------------------------------
# Report.


def _slug(name: str) -> str:
    return re.sub(r"[^a-z0-9]+", "_", name.lower()).strip("_") or "method"


def markdown_report(doc: Mapping) -> str:
    """eval.md: one table per source of cases (method rows, metric columns), the silhouettes, the notes."""
    cfg = doc["config"]
    lines = ["# Retargeting evaluation", ""]
    head = ("| method | pose MSE ×10³ | pose RMSE % | pose PCK@.05 | pose PCK@.1 | range of motion | "
            "with root MSE ×10³ | with root PCK@.1 | placed MSE ×10³ | placed PCK@.1 |")  # fmt: skip
    for source, rows in doc["results"].items():
        lines += [f"## {source}: {cfg['pairs']} cases of {cfg['length']} frames", "", head, "|---" * 10 + "|"]
        for name, r in rows.items():
            p, w, pl = r["pose"], r["with_root"], r["placed"]
            lines.append(
                f"| {name} | {p['mse_x1e3']:.2f} ± {p['mse_x1e3_se']:.2f} | {p['rmse_pct']:.1f} | "
                f"{p['pck_0.05']:.3f} | {p['pck_0.1']:.3f} | {p['amplitude']:.2f} | "
                f"{w['mse_x1e3']:.2f} ± {w['mse_x1e3_se']:.2f} | "
                f"{w['pck_0.1']:.3f} | {pl['mse_x1e3']:.2f} | {pl['pck_0.1']:.3f} |"
            )
        lines.append("")
    if doc.get("real_pairs"):
        from retarget.evaluate_real import markdown_rows

        lines += ["## Real tracks (no ground truth)", "", *markdown_rows(doc["real_pairs"]), ""]
    if doc["silhouettes"]:
        lines += ["## Mean silhouette coefficients of the codes", "",
                  "| network | motion codes (by motion) | skeleton codes (by character) | view codes (by view) |",
                  "|---|---|---|---|"]  # fmt: skip
        for name, s in doc["silhouettes"].items():
            cells = [f"{s[k]:.3f}" if k in s else "–" for k in ("motion", "body", "view")]
            lines.append(f"| {name} | " + " | ".join(cells) + " |")
        lines.append("")
    lines += ["## Notes", ""] + [f"- {n}" for n in doc["notes"]]
    return "\n".join(lines) + "\n"


def _notes(doc: Mapping) -> list[str]:
    cfg = doc["config"]
    notes = [
        (f"Cases: {cfg['pairs']} per source, seed {cfg['seed']}: the motion of a window performed by character A "
         f"seen by camera A, moved onto character B (≠ A) seen by camera B (13 view bins, pitch uniform in "
         f"±{cfg['max_pitch']:g}°). Truth: the same 3D motion replayed on B's skeleton (bone directions kept, root "
         "path scaled by the leg ratio, feet on the ground) and projected by camera B."),
        (f"Reference: a {cfg['reference_length']}-frame window of another motion performed by B and seen by camera "
         "B. Networks take B's skeleton and view codes and the placement from it, the 2D baselines their scale "
         "statistics. The 3D references see the true 3D motion and camera instead."),
        ("Units: coordinates are divided by h, B's height in pixels (skeleton height × pixels per metre). MSE: "
         "mean over frames, joints and x/y of the squared difference, ×10³ (units h² × 10⁻³), ± its standard "
         "error over cases. RMSE: root mean squared joint distance of a case in % of h, averaged over cases. "
         "PCK@a: share of joints within a·h."),
        ("pose: each frame's MidHip subtracted from prediction and truth, the 14 other joints scored (the "
         "paper's numbers are about the pose). with root: all 15 joints, after removing the one translation per "
         "case that best aligns prediction and truth (the root trajectory counts, where in the frame the "
         "reference stood does not). placed: the output as it lands in the reference's frame."),
        ("Range of motion: the summed RMS distance of the joints from their mean positions (MidHip removed), "
         "in units of the body's height, of the output over the truth's (1 = neither damped nor exaggerated). "
         "On real tracks it is the output's over the driver's."),
    ]
    for name, method in doc["methods"].items():
        what = method["description"]
        if method.get("weights"):
            what += f"; weights {method['weights']}"
        notes.append(f"{name}: {what}.")
    notes += doc.get("remarks", [])
    if doc["silhouettes"]:
        notes.append(f"Silhouettes: codes of {cfg['code_samples']} windows of distinct motions × "
                     f"{cfg['code_samples']} characters × up to {cfg['code_samples']} views of the split (pitch 0); "
                     "~1 = clusters by the label, ~0 = the label does not explain the codes. Plots: codes_*.png, "
                     "first two principal components.")  # fmt: skip
    return notes


def run_eval(
    split: WorldSplit,
    out: str | Path,
    *,
    weights: str | Path | None = None,
    compare: Mapping[str, str | Path] | None = None,
    official: str | Path | None = None,
    bvh: Sequence[str | Path] = (),
    real: Mapping[str, PoseTrack] | None = None,
    config: EvalConfig = EvalConfig(),
    fps: float = 30.0,
    device: str = "cpu",
    overwrite: bool = False,
    world_seed: int | None = None,
    progress: Progress | None = None,
) -> tuple[dict, str]:
    """Evaluate every method; write ``eval.json``, ``eval.md`` and ``codes_<network>.png`` into ``out`` atomically.

    Args:
        split: the world split the cases, characters and references come from.
        out: output folder (must not exist unless ``overwrite``).
        weights: our checkpoint; None = the shipped weights when present (otherwise no "ours" row).
        compare: more checkpoints, row name -> path (e.g. ablations).
        official: folder with the authors' ``pretrained_{full,skeleton,view}.pth`` and statistics; a row for
            each file found.
        bvh: extra mocap files, replayed on the split's characters as a second source of cases.
        real: real tracks by name; every ordered pair is retargeted by every network and baseline and
            measured without ground truth (:mod:`retarget.evaluate_real`).
        config: what is evaluated.
        fps: the world's frame rate.
        device: where the networks run.
        overwrite: replace an existing ``out``.
        world_seed: the seed ``split``'s world was built with; a checkpoint trained on another world's split
            (its recorded training seed differs) gets a warning in the notes, as its training motions may be
            among the cases.
        progress: ``progress(done, total)`` over all cases and silhouette grids.

    Returns:
        ``(document written to eval.json, markdown of eval.md)``.

    Raises:
        InputError: an existing ``out``, unreadable weights or mocap, a clash of row names, an ``official``
            folder without any of the authors' weights, or a split too small to evaluate.
    """
    from retarget.api import PACKAGED_WEIGHTS
    from retarget.world.rigs import load_motion

    started = time.perf_counter()
    out = Path(out)
    check_new_output(out, overwrite)
    methods: dict[str, Method] = {}
    nets: dict[str, object] = {}
    info: dict[str, dict[str, str]] = {}
    remarks: list[str] = []

    def add_network(name: str, path: Path, description: str) -> None:
        if name in methods or name in BASELINES or name in REFERENCES_3D:
            raise InputError(f"--compare {name}: that row name is taken; choose another")
        methods[name], nets[name] = network_method(path, device)
        info[name] = {"kind": "network", "description": description, "weights": str(path)}
        trained = _training_seed(path)
        if world_seed is not None and trained is not None and trained != world_seed:
            remarks.append(f"Warning: {name} was trained on the world of seed {trained}, these cases come from the "
                           f"world of seed {world_seed}: its training motions may be among them (--world-seed).")

    if weights is None and PACKAGED_WEIGHTS.is_file():
        weights = PACKAGED_WEIGHTS
    if weights is not None:
        add_network("ours", Path(weights), DESCRIPTIONS["ours"])
    else:
        remarks.append("ours: not evaluated (no --weights and no shipped weights).")
    for name, path in (compare or {}).items():
        add_network(name, Path(path), "another checkpoint, run like ours")
    if official is not None:
        found = {name: Path(official) / file for name, file in OFFICIAL_FILES.items()
                 if (Path(official) / file).is_file()}  # fmt: skip
        if not found:
            raise InputError(f"{official}: none of {', '.join(OFFICIAL_FILES.values())} is there")
        for name, path in found.items():
            add_network(name, path, DESCRIPTIONS[name])
    else:
        remarks.append("authors' released model: not evaluated (no --official folder).")
    for name, method in BASELINES.items():
        methods[name] = method
        info[name] = {"kind": "2D baseline", "description": DESCRIPTIONS[name]}
    for name in REFERENCES_3D:
        info[name] = {"kind": "3D reference", "description": DESCRIPTIONS[name]}

    sources: dict[str, ClipMotions | None] = {f"{split.name} split": None}
    if bvh:
        clips = [load_motion(path, fps=fps) for path in bvh]
        sources[f"extra mocap ({len(clips)} clip{'s' if len(clips) > 1 else ''})"] = ClipMotions(
            clips, split.characters, config.length, max(1, config.length // 2)
        )
    total = config.pairs * len(sources) + len(nets)
    done = 0

    def tick(step: int, _: int) -> None:
        if progress is not None:
            progress(done + step, total)

    results = {}
    for source_name, motions in sources.items():
        results[source_name] = evaluate(split, methods, config, motions, fps, tick)
        done += config.pairs
    real_results = {}
    if real:
        from retarget.evaluate_real import real_pair_results

        real_results = real_pair_results(real, {n: m for n, m in methods.items() if n in nets or n in BASELINES})
    silhouettes, plots = {}, {}
    for name, net in nets.items():
        scores, codes, labels = code_silhouettes(net, split, config, fps)
        silhouettes[name] = scores
        plots[name] = (codes, labels)
        done += 1
        tick(0, total)

    doc: dict = {
        "config": asdict(config),
        "split": split.name,
        "world": {
            "motions": split.num_motions, "characters": list(split.character_names), "views": list(split.views),
            "canvas_size": list(split.canvas_size),
        },
        "extra_mocap": [str(p) for p in bvh],
        "methods": info,
        "results": results,
        "real_pairs": real_results,
        "silhouettes": silhouettes,
        "remarks": remarks,
    }
    doc["notes"] = _notes(doc)
    files: dict[str, str] = {}
    for name in plots:
        file = f"codes_{_slug(name)}.png"
        files[name] = file if file not in files.values() else f"codes_{_slug(name)}_{len(files)}.png"
    doc["code_plots"] = files
    with atomic_dir(out, overwrite=overwrite) as tmp:
        for name, (codes, labels) in plots.items():
            plot_codes(tmp / files[name], name, codes, labels, silhouettes[name])
        doc["seconds"] = round(time.perf_counter() - started, 1)
        table = markdown_report(doc)
        (tmp / "eval.json").write_text(json.dumps(doc, indent=2))
        (tmp / "eval.md").write_text(table)
    log.info("evaluation written to %s in %.0f s", out, doc["seconds"])
    return doc, table
