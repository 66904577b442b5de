"""Answering a query: normalised cross-correlation of its features with the whole index, in one pass.

Score of time shift ``s`` (the cosine similarity of two feature windows, both centred on the index mean)::

    score[s] = sum_{c, k} q[c, k] x[c, s + k] / (|q| * |x[:, s : s + L]|)

The numerator of every shift of every track comes from ONE :func:`torch.nn.functional.conv1d` over the
concatenated index with the query as the kernel, its ``P`` phases x ``L`` taps laid out as ``P * L`` output
channels of a pointwise convolution, followed by ``L`` shifted adds (:func:`correlate`). That is the same sum
as ``conv1d(index, query)``; on the CPU it is 2-10x faster, because oneDNN's direct convolution with few
output channels costs as much for 1 phase as for 8 and grows with ``L`` (see bench/search.py). The window norms
come from a running sum of squared step norms. Shifts whose window straddles two tracks are masked. Since
the score is a cosine, long and short tracks, loud and quiet motions compare on one scale in [-1, 1].

Phases: a query cut from an indexed track rarely starts on the 8-frame code grid, so it is encoded at its 8
phases (:func:`~retarget.applications.search.features.query_features`). The one pass runs at most ``KERNEL_BUDGET`` query
steps x phases (all 8 phases for queries up to 71 frames, 4 up to 135, 2 up to 263, then 1), so a long query
costs about what a short one does; each hit is then refined with all phases at its shift and the two next to
it, which keeps starts frame-accurate.

Hits: the best shift of every track, the K best tracks; with ``per_track > 1``, further peaks of a track
after non-maximum suppression of shifts that overlap an accepted hit by more than ``overlap``.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
import torch
import torch.nn.functional as F

from pose_io.errors import InputError
from pose_io.track import PoseTrack
from retarget.applications.search.features import TrackEncoder, at_encoder_fps, query_features
from retarget.applications.search.index import SearchIndex

#: Most (query steps x phases) the one pass over the index correlates: bounds a query's cost.
KERNEL_BUDGET = 64
#: Peaks of a track refined with every phase when the pass used fewer.
REFINED_PEAKS = 8


@dataclass(frozen=True)
class Match:
    """One hit.

    Attributes:
        path: the indexed track.
        track: its position in the index.
        start: first matching frame, in the track's own frames.
        end: one past the last matching frame (``start + the query's duration``, clipped to the track).
        score: cosine similarity in [-1, 1].
    """

    path: str
    track: int
    start: int
    end: int
    score: float

    def to_dict(self) -> dict[str, object]:
        return asdict(self)


def check_encoder(index: SearchIndex, encoder: TrackEncoder) -> None:
    """InputError unless ``encoder`` made the features of ``index``."""
    if (index.kind, index.digest) != (encoder.kind, encoder.digest):
        raise InputError(
            f"search index: built from {index.kind} features of encoder {index.digest}, the query uses"
            f" {encoder.kind} features of encoder {encoder.digest}; rebuild the index or pass the same --weights"
        )


def search(
    index: SearchIndex,
    encoder: TrackEncoder,
    query: PoseTrack,
    top_k: int = 10,
    per_track: int = 1,
    overlap: float = 0.0,
    phase_step: int | None = None,
    tracks: np.ndarray | None = None,
    name: str = "query",
) -> list[Match]:
    """The tracks of ``index`` that hold the motion of ``query``, best first.

    Args:
        index: from :func:`~retarget.applications.search.index.build_index` or :func:`~retarget.applications.search.index.load_index`.
        encoder: the encoder the index was built with.
        query: the query track (any length the encoder takes, any layout with body15).
        top_k: hits to return.
        per_track: most hits from one track.
        overlap: largest share of the query's length two hits in one track may share.
        phase_step: frames between the query phases of the pass over the whole index (None: as many phases as
            ``KERNEL_BUDGET`` allows); hits are refined with every phase.
        tracks: [M] bool, the tracks that may be returned (default all).
        name: how error messages call the query.

    Returns:
        Up to ``top_k`` matches; fewer when fewer tracks are as long as the query.

    Raises:
        InputError: another encoder built the index, or the query is too short.
    """
    check_encoder(index, encoder)
    features, phases = query_features(encoder, query, 1, name)
    length = len(at_encoder_fps(query, encoder))
    return rank(index, features, phases, length / encoder.fps, top_k, per_track, overlap, tracks, phase_step)


def correlate(index: SearchIndex, features: np.ndarray | torch.Tensor) -> torch.Tensor:
    """Normalised cross-correlation of query features with every shift of the index.

    Args:
        index: the index.
        features: [P, C, L] uncentred query features (one sequence per phase).

    Returns:
        [P, N - L + 1] float32 cosine scores, -inf where the window straddles two tracks; [P, 0] when the
        query is longer than the whole index.
    """
    q = torch.as_tensor(features, dtype=torch.float32) - index.center[None, :, None]  # [P, C, L]
    length = q.shape[-1]
    shifts = index.num_steps - length + 1
    if shifts <= 0:
        return torch.empty(q.shape[0], 0)
    score = _cosines(index.features, index.step_cumsum, q).float()  # [P, S]
    same = index.track_of_step[:shifts] == index.track_of_step[length - 1 :]  # [S] window inside one track
    return score.masked_fill(~same[None], -math.inf)


def _cosines(x: torch.Tensor, cumsum: torch.Tensor, q: torch.Tensor) -> torch.Tensor:
    """Cosine of the query with every window of a run of steps.

    Args:
        x: [C, n] centred feature steps.
        cumsum: [n + 1] running sum of their squared norms (any constant offset).
        q: [P, C, L] centred query, n >= L.

    Returns:
        [P, n - L + 1] float64.
    """
    phases, channels, length = q.shape
    shifts = x.shape[1] - length + 1
    taps = q.permute(0, 2, 1).reshape(phases * length, channels, 1)  # [P * L, C, 1]: tap k of phase p
    products = F.conv1d(x[None], taps)[0].view(phases, length, -1)  # [P, L, n]
    num = products[:, 0, :shifts].clone()  # [P, S]
    for k in range(1, length):
        num += products[:, k, k : k + shifts]  # tap k meets step s + k
    windows = (cumsum[length:] - cumsum[:-length]).clamp_min(0).sqrt()  # [S] float64
    den = q.flatten(1).norm(dim=1, keepdim=True).double() * windows[None]  # [P, S]
    return num.double() / den.clamp_min(1e-12)


def rank(
    index: SearchIndex,
    features: np.ndarray | torch.Tensor,
    phases: np.ndarray,
    seconds: float,
    top_k: int = 10,
    per_track: int = 1,
    overlap: float = 0.0,
    tracks: np.ndarray | None = None,
    phase_step: int | None = None,
) -> list[Match]:
    """Best matches of precomputed query features (see :func:`search` for the other arguments).

    Args:
        features: [P, C, L] query features at every phase, phase ``phases[p]`` in row ``p``.
        phases: [P] frames the query's phases drop at its start (at the index's rate), increasing.
        seconds: the query's duration (sets each hit's end).
    """
    if top_k < 1 or per_track < 1 or not 0.0 <= overlap < 1.0:
        raise ValueError("top_k and per_track must be >= 1 and overlap in [0, 1)")
    features = torch.as_tensor(features, dtype=torch.float32)
    length = features.shape[-1]  # L, query steps
    coarse = _coarse_rows(phases, length, phase_step)
    scores = correlate(index, features[coarse])  # [P', S]
    if scores.shape[1] == 0:
        return []
    best, _ = scores.max(dim=0)  # [S]
    if tracks is not None:
        allowed = torch.as_tensor(np.asarray(tracks, dtype=bool))
        if allowed.shape != (index.num_tracks,):
            raise ValueError(f"tracks must be [{index.num_tracks}] bool, got shape {tuple(allowed.shape)}")
        best = best.masked_fill(~allowed[index.track_of_step[: best.shape[0]]], -math.inf)
    per_track_best = torch.full((index.num_tracks,), -math.inf).scatter_reduce(
        0, index.track_of_step[: best.shape[0]], best, reduce="amax"
    )  # [M]
    # Only the K tracks with the best peaks can hold the K best hits: every other hit scores below K of them.
    order = torch.argsort(per_track_best, descending=True)[:top_k]
    radius = max(1, math.ceil(length * (1.0 - overlap)))
    # With fewer phases in the pass, a periodic motion may peak one cycle off: refine a few peaks, keep the best.
    refine = 1 if len(coarse) == len(phases) else REFINED_PEAKS
    found: list[tuple[float, int, int, int]] = []  # (score, track, step, phase)
    for t in order.tolist():
        if not math.isfinite(float(per_track_best[t])):
            break
        lo, hi = int(index.offsets[t]), int(index.offsets[t + 1]) - length + 1
        local = best[lo:hi].clone()
        accepted: list[int] = []  # steps of this track's hits
        while len(accepted) < per_track and math.isfinite(float(local.max())):
            peaks = _peaks(local, refine)
            hit = max((_refine(index, features, t, lo + s) for s in peaks), key=lambda h: h[0])
            s = hit[2] - lo
            # Refinement may move a peak a step into the zone of an accepted hit: such a hit is not taken.
            if all(abs(s - a) >= radius for a in accepted):
                found.append(hit)
                accepted.append(s)
            for centre in {s, *peaks[:1]}:
                local[max(0, centre - radius + 1) : centre + radius] = -math.inf
    found.sort(key=lambda item: -item[0])
    return [_match(index, t, s, int(phases[p]), seconds, v) for v, t, s, p in found[:top_k]]


def _coarse_rows(phases: np.ndarray, length: int, phase_step: int | None) -> list[int]:
    """Rows of the phases the pass over the whole index uses (evenly spaced, the first always)."""
    if phase_step is None:
        every = 1
        while -(-len(phases) // every) * length > KERNEL_BUDGET and every < len(phases):
            every *= 2
        return list(range(0, len(phases), every))
    return [k for k, p in enumerate(phases) if p % max(1, phase_step) == 0] or [0]


def _peaks(scores: torch.Tensor, count: int) -> list[int]:
    """Positions of the ``count`` highest local maxima of [n] ``scores`` (finite ones), best first."""
    padded = F.pad(scores[None, None], (1, 1), value=-math.inf)[0, 0]  # [n + 2]
    is_peak = (scores >= padded[:-2]) & (scores >= padded[2:]) & torch.isfinite(scores)
    where = torch.nonzero(is_peak)[:, 0]
    return where[torch.argsort(scores[where], descending=True)[:count]].tolist()


def _refine(index: SearchIndex, features: torch.Tensor, track: int, step: int) -> tuple[float, int, int, int]:
    """The best (score, track, step, phase) with every phase at ``step`` and its neighbours in ``track``."""
    length = features.shape[-1]
    first = max(int(index.offsets[track]), step - 1)
    last = min(int(index.offsets[track + 1]) - length, step + 1)
    q = features - index.center[None, :, None]  # [P, C, L]
    score = _cosines(index.features[:, first : last + length], index.step_cumsum[first : last + length + 1], q)
    phase, shift = divmod(int(torch.argmax(score)), score.shape[1])  # score: [P, last - first + 1]
    return float(score[phase, shift]), track, first + shift, phase


def _match(index: SearchIndex, track: int, step: int, dropped: int, seconds: float, score: float) -> Match:
    """A hit at global ``step`` of ``track`` for the query phase that dropped ``dropped`` frames."""
    ratio = index.track_fps[track] / index.fps  # own frames per encoder frame
    first = max(0, (step - int(index.offsets[track])) * index.stride - dropped)  # encoder frames
    frames = int(index.frames[track])
    start = min(frames - 1, round(float(first * ratio)))
    end = min(frames, start + max(1, round(float(seconds * index.track_fps[track]))))
    return Match(index.paths[track], track, start, end, score)
