"""Cases of the motion world (see the package docstring): sampling them and scoring every method on them."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from pose_io.errors import InputError
from retarget.evaluate.config import DEFAULT_CONFIG, EvalConfig, Method, Progress
from retarget.evaluate.references3d import REFERENCE_FUNCTIONS
from retarget.evaluate.scores import CaseScores, case_scores, summarise
from retarget.evaluate.turns import MotionSource
from retarget.inference.tracks import body15_track
from retarget.inference.windows import strided_starts
from retarget.world.skeleton import Motion3D, Skeleton, joint_index, retarget_3d
from retarget.world.split import WindowLabel, WorldSplit

_WORLD_ROOT = joint_index("mid_hip")


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
            for start in strided_starts(m.num_frames, window, stride):
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


def _reference_candidates(
    motions: MotionSource, split: WorldSplit, config: EvalConfig
) -> dict[int, list[int]]:
    """Evaluated window -> the reference windows of ``split`` it may take, for every window long enough."""
    labels, refs_all = motions.window_labels, split.window_labels
    refs = [r for r, lab in enumerate(refs_all) if lab.clip_frames - lab.start >= config.reference_length]
    candidates: dict[int, list[int]] = {}
    for m, lab in enumerate(labels):
        if lab.clip_frames - lab.start < config.length:
            continue
        other = [r for r in refs if refs_all[r].group != lab.group]
        if not other:  # a one-motion split: any window that shares no frame with the case
            other = [r for r in refs if not _overlaps(lab, config.length, refs_all[r], config.reference_length)]
        if other:
            candidates[m] = other
    return candidates


def sample_cases(
    motions: MotionSource, split: WorldSplit, config: EvalConfig, rng: np.random.Generator
) -> list[Case]:
    """``config.pairs`` cases of ``motions`` with references from ``split`` (see the package docstring).

    Raises:
        InputError: no window long enough, fewer than two characters, or no reference window that shares no
            frame with a case.
    """
    if split.num_characters < 2:
        raise InputError(f"{split.name} split: retargeting needs at least two characters")
    candidates = _reference_candidates(motions, split, config)
    if not candidates:
        raise InputError(f"{split.name} split: no {config.length}-frame window with a reference window of "
                         f"{config.reference_length} frames that shares none of its frames")  # fmt: skip
    fits = sorted(candidates)
    # With every bin allowed this draws exactly what the protocol drew before it had max_yaw.
    views = np.flatnonzero(np.abs(np.asarray(split.views)) <= config.max_yaw + 1e-9)
    if not len(views):
        raise InputError(f"{split.name} split: no view within {config.max_yaw:g} degrees of the front")
    cases = []
    for _ in range(config.pairs):
        m = fits[rng.integers(len(fits))]
        ca, cb = rng.choice(split.num_characters, size=2, replace=False)
        va, vb = views[rng.integers(0, len(views), size=2)]
        pa, pb = rng.uniform(-config.max_pitch, config.max_pitch, size=2)
        ref = candidates[m][rng.integers(len(candidates[m]))]
        cases.append(Case(m, int(ca), int(va), float(pa), int(cb), int(vb), float(pb), ref))
    return cases


def _score_case(
    case: Case, split: WorldSplit, source: MotionSource, methods: Mapping[str, Method],
    config: EvalConfig, fps: float, noise: np.random.Generator | None = None,
) -> dict[str, CaseScores]:  # fmt: skip
    """Row -> :func:`case_scores` of one case, for every method and then every 3D reference.

    ``noise`` draws the detector noise of the method inputs (``config.noise``; None: clean inputs).
    """
    skel_a, skel_b = split.characters[case.source_character], split.characters[case.character]
    pos_a = source.window3d(case.motion, case.source_character, config.length)  # [L, 18, 3]
    pos_b = source.window3d(case.motion, case.character, config.length)
    ref3d = split.window3d(case.reference, case.character, config.reference_length)
    motion2d = split.project(pos_a[None], [case.source_view], pitch_deg=[case.source_pitch])[0]  # [L, 15, 2]
    reference2d = split.project(ref3d[None], [case.view], pitch_deg=[case.pitch])[0]
    built = [f(pos_a, skel_a, skel_b) for f in REFERENCE_FUNCTIONS.values()]
    seen = split.project(np.stack([pos_b, *built]), [case.view] * (1 + len(built)),
                         pitch_deg=[case.pitch] * (1 + len(built)))  # fmt: skip  # [1 + R, L, 15, 2]
    truth = seen[0]
    scale = split.camera(case.view).scale  # pixels per metre, the same for every view
    height = skel_b.height * scale  # pixels
    if noise is not None:
        motion2d = motion2d + noise.normal(0.0, config.noise * skel_a.height * scale, motion2d.shape)
        reference2d = reference2d + noise.normal(0.0, config.noise * height, reference2d.shape)
    size = tuple(split.canvas_size)
    motion_track = body15_track(motion2d, fps, size)
    reference_track = body15_track(reference2d, fps, size)
    scores = {name: case_scores(method(motion_track, reference_track).joints, truth, height)
              for name, method in methods.items()}  # fmt: skip
    for name, pred in zip(REFERENCE_FUNCTIONS, seen[1:]):
        scores[name] = case_scores(pred, truth, height)
    return scores


def evaluate(
    split: WorldSplit,
    methods: Mapping[str, Method],
    config: EvalConfig = DEFAULT_CONFIG,
    motions: MotionSource | None = None,
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
    rows: dict[str, list[CaseScores]] = {name: [] for name in [*methods, *REFERENCE_FUNCTIONS]}
    for k, case in enumerate(cases):
        noise = np.random.default_rng([config.seed, 104723, k]) if config.noise > 0 else None
        for name, scores in _score_case(case, split, source, methods, config, fps, noise).items():
            rows[name].append(scores)
        if progress is not None:
            progress(k + 1, len(cases))
    return {name: summarise(scores) for name, scores in rows.items()}
