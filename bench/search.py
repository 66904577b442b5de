"""Stage `search`: motion retrieval (``retarget.applications.search``) query time against index size, and index building.

Index: tracks of 500-1500 frames (about 1,000 on average) cut from the source track tiled forwards and
backwards, each at its own offset, encoded once with the shipped network; the larger indexes repeat the
encoded tracks of the 100,000-frame one (query time depends on the number of code steps, not on what they
hold). Sizes: 10,000, 100,000 and 1,000,000 frames (``--quick``: 10,000, 100,000 and 300,000), and the largest
again as clips of 104 frames (about 10,000 tracks).

Ours: ``search()`` end to end (the query's motion code at its 8 phases, then ONE ``conv1d`` over the
concatenated index with as many phases as ``KERNEL_BUDGET`` allows - 8 for the 64-frame query, 2 for the
256-frame one - normalisation, masking of shifts that straddle tracks, the best shift per track, top 10 and
their refinement with all phases), for a 64-frame (2 s) and a 256-frame query, on 2 threads and on 1.
Baseline, same run: the same normalised cross-correlation with the same phases as a per-track loop (one
``conv1d`` per track, its own window norms, its best shift), given the query codes (so it is not charged for
encoding the query); the one pass finds the same 10 best scores (``top10_score_diff``). Also timed: the one
pass written as a plain ``conv1d(index, query)``, which oneDNN runs as a direct convolution whose cost hardly
depends on the number of phases and grows with the query's length (why ``correlate`` uses a pointwise
convolution over the query's taps and shifted adds instead).
Also: frames/s of building the index (reading excluded: tracks are in memory), the file size of the saved
index and the time ``load_index`` takes.
"""

from __future__ import annotations

import math
import shutil
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
import torch
import torch.nn.functional as F

from bench.data import source_track, tiled
from bench.harness import row, time_call

TRACK_FRAMES = (500, 1500)


def _one_pass(index: Any, features: np.ndarray, top_k: int) -> list[float]:
    """Ours without refinement: the best score of the K best tracks from the one pass. features [P, C, L]."""
    from retarget.applications.search import correlate

    best = correlate(index, features).max(dim=0).values  # [S]
    per_track = torch.full((index.num_tracks,), -math.inf).scatter_reduce(
        0, index.track_of_step[: best.shape[0]], best, reduce="amax")  # fmt: skip
    return per_track.sort(descending=True).values[:top_k].tolist()


def _direct_one_pass(index: Any, features: np.ndarray, top_k: int) -> list[float]:
    """The one pass as a plain ``conv1d(index, query)`` (oneDNN direct convolution): best scores of K tracks."""
    q = torch.as_tensor(features) - index.center[None, :, None]  # [P, C, L]
    length = q.shape[-1]
    num = F.conv1d(index.features[None], q)[0]  # [P, S]
    windows = (index.step_cumsum[length:] - index.step_cumsum[:-length]).clamp_min(0).sqrt().float()  # [S]
    score = num / (q.flatten(1).norm(dim=1, keepdim=True) * windows[None]).clamp_min(1e-12)
    same = index.track_of_step[: score.shape[1]] == index.track_of_step[length - 1 :]
    best = score.masked_fill(~same[None], -math.inf).max(dim=0).values  # [S]
    per_track = torch.full((index.num_tracks,), -math.inf).scatter_reduce(
        0, index.track_of_step[: best.shape[0]], best, reduce="amax")  # fmt: skip
    return per_track.sort(descending=True).values[:top_k].tolist()


def _per_track_loop(index: Any, features: np.ndarray, top_k: int) -> list[tuple[float, int]]:
    """Baseline: the same cosine scores track by track. features [P, C, L] -> [(score, track)] best first."""
    q = torch.as_tensor(features) - index.center[None, :, None]  # [P, C, L]
    length = q.shape[-1]
    qn = q.flatten(1).norm(dim=1, keepdim=True)  # [P, 1]
    ones = torch.ones(1, 1, length)
    best = []
    for t in range(index.num_tracks):
        x = index.track_features(t)  # [C, T]
        if x.shape[1] < length:
            continue
        num = F.conv1d(x[None], q)[0]  # [P, T - L + 1]
        norms = F.conv1d(x.square().sum(0)[None, None], ones)[0].clamp_min(0).sqrt()  # [1, T - L + 1]
        best.append((float((num / (qn * norms).clamp_min(1e-12)).max()), t))
    best.sort(key=lambda item: -item[0])
    return best[:top_k]


def run(quick: bool = False, repeats: int | None = None, **_: object) -> dict[str, Any]:
    from retarget.api import PACKAGED_WEIGHTS, load_retargeter
    from retarget.applications.search import MotionCodeEncoder, from_sequences, load_index, save_index, search
    from retarget.applications.search.features import query_features, track_features
    from retarget.applications.search.query import _coarse_rows, rank

    threads_before = torch.get_num_threads()
    torch.set_num_threads(1)
    reps = repeats or (3 if quick else 5)
    source, origin = source_track()
    encoder = MotionCodeEncoder(load_retargeter(PACKAGED_WEIGHTS, device="cpu"))
    rng = np.random.default_rng(0)

    # 100 tracks = 100,000 frames on average, encoded for real; the build rate is measured on them.
    lengths = rng.integers(TRACK_FRAMES[0], TRACK_FRAMES[1] + 1, size=100)
    offsets = rng.integers(0, 2 * source.num_frames, size=100)
    long = tiled(source, int(offsets.max() + lengths.max()))
    tracks = [long.frames(int(o), int(o + n)) for o, n in zip(offsets, lengths)]
    t0 = time.perf_counter()
    codes = [track_features(encoder, t) for t in tracks]
    build_s = time.perf_counter() - t0
    base_frames = int(lengths.sum())

    sizes = (10_000, 100_000, 300_000 if quick else 1_000_000)
    queries = {"query 64 frames": tiled(source, 64 + 13).frames(13, 77), "query 256 frames": tiled(source, 256)}
    rows = [row("index build", "track_features, 100 tracks in memory", base_frames / build_s, "frames/s",
                tracks=len(tracks), frames=base_frames)]  # fmt: skip
    # The same codes cut into clips of 13 steps (104 frames): many short tracks, where a per-track loop suffers.
    clips = [c[:, k : k + 13] for c in codes for k in range(0, c.shape[1] - 12, 13)]
    layouts = [(size, "tracks of 500-1500 frames", codes, [len(t) for t in tracks]) for size in sizes]
    layouts.append((sizes[-1], "clips of 104 frames", clips, [104] * len(clips)))
    notes = []
    tmp = Path(tempfile.mkdtemp(prefix="bench_search_"))
    try:
        for size, what, sequences, frames_of in layouts:
            reps_here = reps if size < 1_000_000 else max(2, reps - 2)
            per = sum(frames_of) / len(frames_of)
            n_tracks = max(1, round(size / per))
            picks = [k % len(sequences) for k in range(n_tracks)]
            index = from_sequences([sequences[k] for k in picks], [f"track{k}" for k in range(n_tracks)],
                                   [source.fps] * n_tracks, [frames_of[k] for k in picks], encoder)  # fmt: skip
            frames = index.num_frames
            case = f"index {frames:,} frames ({n_tracks:,} {what})"
            for qname, query in queries.items():
                if what.startswith("clips") and qname != "query 64 frames":
                    continue
                features, phases = query_features(encoder, query)
                coarse = features[_coarse_rows(phases, features.shape[-1], None)]  # the phases of the one pass
                plain = "per-track loop of conv1d, same scores (query codes given)"
                torch.set_num_threads(1)
                base = time_call(lambda f=coarse, i=index: _per_track_loop(i, f, 10), reps_here, 1)
                theirs = [v for v, _ in _per_track_loop(index, coarse, 10)]
                diff = float(np.max(np.abs(np.subtract(_one_pass(index, coarse, 10), theirs))))
                for threads in (2, 1):
                    torch.set_num_threads(threads)
                    end = time_call(lambda q=query, i=index: search(i, encoder, q, top_k=10), reps_here, 1)
                    core = time_call(lambda f=features, p=phases, i=index: rank(i, f, p, 2.0, 10), reps_here, 1)
                    rows.append(row(f"{case}, {qname}", f"search() end to end, {threads} thread(s)", end.median_s,
                                    "s", base.median_s, plain, higher_is_better=False, frames=frames,
                                    steps=index.num_steps, query_steps=features.shape[-1], phases=len(coarse),
                                    rank_only_s=round(core.median_s, 4), top10_score_diff=diff))  # fmt: skip
                torch.set_num_threads(1)
                direct = time_call(lambda f=coarse, i=index: _direct_one_pass(i, f, 10), reps_here, 1)
                rows.append(row(f"{case}, {qname}", "one pass as plain conv1d(index, query), 1 thread",
                                direct.median_s, "s", base.median_s, plain, higher_is_better=False, phases=len(coarse),
                                top10_score_diff=float(np.max(np.abs(np.subtract(
                                    _direct_one_pass(index, coarse, 10), theirs))))))  # fmt: skip
            torch.set_num_threads(1)
            if what.startswith("tracks"):
                path = save_index(index, tmp / f"index_{size}.npz")
                load = time_call(lambda p=path: load_index(p), max(2, reps_here - 2), 1)
                rows.append(row(case, "load_index (npz, float16 codes)", load.median_s, "s", higher_is_better=False,
                                file_mb=round(path.stat().st_size / 2**20, 1)))  # fmt: skip
        notes += [
            (f"input: {origin}, tiled; tracks of {TRACK_FRAMES[0]}-{TRACK_FRAMES[1]} frames; weights "
             f"{PACKAGED_WEIGHTS.name}; index of {sizes[-1]:,} frames repeats the 100,000-frame one's codes"),
            ("queries: the 64-frame one starts 13 frames into the source (off the 8-frame code grid); phases = those"
             " of the one pass"),
            "rank_only_s: the one-pass correlation + top 10 without encoding the query (the baseline's share)",
            ("top10_score_diff: largest difference between the 10 best per-track scores of the one pass and of the"
             " baseline (the larger indexes repeat tracks, so tied tracks may come in another order)"),
            (f"query time grows linearly with the index: ~{_slope(rows):.2g} s per million frames (2 threads, "
             "64-frame query)"),
        ]
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
        torch.set_num_threads(threads_before)
    return {"rows": rows, "notes": notes}


def _slope(rows: list[dict[str, Any]]) -> float:
    """Seconds per million frames of the largest index (2 threads, 64-frame query)."""
    picked = [r for r in rows if "tracks of" in r["case"] and "64 frames" in r["case"]
              and r["variant"].endswith("2 thread(s)")]
    if not picked:
        return math.nan
    last = max(picked, key=lambda r: r["extra"]["frames"])
    return last["value"] / last["extra"]["frames"] * 1e6
