"""retarget.applications.search.query: the one-pass search over an index, its hits, the encoders it compares."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest
import torch

from pose_io.errors import InputError
from pose_io.resample import resample
from pose_io.track import PoseTrack
from retarget.applications.search import JointEncoder, MotionCodeEncoder, correlate, from_sequences, search
from retarget.applications.search.features import query_features, track_features
from tests.retarget.applications.search.moving import FRAMES, moving_figure


def test_features_are_the_network_codes_in_steps_of_8(encoder, tracks, index):
    assert index.num_tracks == 4 and index.num_steps == 4 * FRAMES // 8
    assert list(index.offsets) == [0, 20, 40, 60, 80]
    x = encoder.retargeter._input(tracks[1], "t1")  # [1, 30, T]
    with torch.inference_mode():
        codes = encoder.retargeter.model.encode_motion(x)[0]  # [128, T/8]
    assert torch.allclose(index.track_features(1) + index.center[:, None], codes, atol=1e-5)
    # Long tracks go through the network in pieces; the seams are cut away, the codes stay the same.
    chunked = MotionCodeEncoder(encoder.retargeter, chunk=32)
    assert np.allclose(track_features(chunked, tracks[1]), codes.numpy(), atol=1e-5)


@pytest.mark.parametrize("start", [40, 37, 83])
def test_a_cut_is_found_where_it_was_cut(encoder, tracks, index, start):
    query = tracks[2].frames(start, start + 64)
    hits = search(index, encoder, query, top_k=4)
    assert hits[0].path == "t2"
    # Within a frame: on these periodic synthetic walkers the neighbouring shift can score a hair higher.
    assert abs(hits[0].start - start) <= 1 and hits[0].end == hits[0].start + 64
    # Not exactly 1: the codes at the query's ends see padding where the index saw the frames around the cut
    # (0.87-0.99 with the shipped weights on these synthetic walkers).
    assert hits[0].score > 0.8
    assert all(h.score < hits[0].score - 0.2 for h in hits[1:])
    assert len({h.path for h in hits}) == 4  # one hit per track by default


def test_frames_are_reported_in_each_tracks_own_frames(encoder, tracks):
    fast = resample(tracks[0], 60.0)  # the same motion filmed at 60 fps: twice the frames
    sequences = [track_features(encoder, t) for t in (fast, tracks[1])]
    index = from_sequences(sequences, ["fast", "t1"], [60.0, 30.0], [len(fast), len(tracks[1])], encoder)
    hits = search(index, encoder, tracks[0].frames(50, 114), top_k=1)
    assert hits[0].path == "fast"
    assert abs(hits[0].start - 100) <= 2 and abs(hits[0].end - 228) <= 2


def test_scores_are_the_cosines_of_the_code_windows(encoder, tracks, index):
    features, _ = query_features(encoder, tracks[3].frames(11, 90))  # [8, 128, 9]
    scores = correlate(index, features).numpy()  # [8, S]
    q = features - index.center.numpy()[None, :, None]
    x = index.features.numpy()
    length = q.shape[-1]
    for p in (0, 5):
        for t in range(index.num_tracks):
            for s in range(index.offsets[t], index.offsets[t + 1] - length + 1):
                window = x[:, s : s + length]
                cosine = (q[p] * window).sum() / np.linalg.norm(q[p]) / np.linalg.norm(window)
                assert scores[p, s] == pytest.approx(cosine, abs=1e-5)
    # The same as one plain conv1d with the query as the kernel.
    plain = torch.nn.functional.conv1d(index.features[None], torch.as_tensor(q))[0]  # [8, S]
    norms = np.sqrt(np.convolve((x**2).sum(0), np.ones(length), mode="valid"))
    direct = plain.numpy() / np.linalg.norm(q.reshape(8, -1), axis=1)[:, None] / norms[None]
    finite = np.isfinite(scores)
    assert np.allclose(scores[finite], direct[finite], atol=1e-5)


def test_shifts_that_straddle_two_tracks_never_match(encoder, tracks, index):
    # The end of track 0 followed by the start of track 1: the one window that holds it is masked.
    joined = PoseTrack(np.concatenate([tracks[0].joints[-40:], tracks[1].joints[:40]]),
                       np.concatenate([tracks[0].confidence[-40:], tracks[1].confidence[:40]]), 30.0,
                       tracks[0].image_size, tracks[0].layout)  # fmt: skip
    features, _ = query_features(encoder, joined)
    scores = correlate(index, features)  # [P, S]
    length = features.shape[-1]
    for boundary in index.offsets[1:-1]:
        assert torch.isinf(scores[:, boundary - length + 1 : boundary]).all()
    assert torch.isfinite(scores[:, : index.offsets[1] - length + 1]).all()
    hits = search(index, encoder, joined, top_k=4)
    for h in hits:
        assert h.end <= FRAMES and h.start >= 0
    # A query longer than every track has no hit.
    assert search(index, encoder, moving_figure(9, frames=FRAMES + 40), top_k=3) == []


def test_non_maximum_suppression_within_a_track(encoder, tracks):
    # One long track that holds the same 64 frames three times, with other motion between them.
    cut = tracks[3].frames(40, 104)
    parts = [tracks[0].frames(0, 48), cut, tracks[1].frames(0, 56), cut, tracks[2].frames(0, 40), cut,
             tracks[0].frames(60, 100)]  # fmt: skip
    joints = np.concatenate([p.joints for p in parts])
    conf = np.concatenate([p.confidence for p in parts])
    long = PoseTrack(joints, conf, 30.0, cut.image_size, cut.layout)
    where = [48, 48 + 64 + 56, 48 + 64 + 56 + 64 + 40]
    sequences = [track_features(encoder, t) for t in (long, tracks[1])]
    index = from_sequences(sequences, ["long", "t1"], [30.0, 30.0], [len(long), len(tracks[1])], encoder)

    assert [h.path for h in search(index, encoder, cut, top_k=5)] == ["long", "t1"]
    hits = search(index, encoder, cut, top_k=3, per_track=5)
    assert [h.path for h in hits] == ["long"] * 3
    assert sorted(h.start for h in hits) == pytest.approx(where, abs=2)
    assert all(h.score > 0.8 for h in hits)
    starts = sorted(h.start for h in search(index, encoder, cut, top_k=10, per_track=10) if h.path == "long")
    # Accepted hits of one track never overlap (overlap=0) ...
    assert all(b - a >= 64 - 8 for a, b in itertools.pairwise(starts)), starts
    # ... unless allowed to: with overlap 0.5 they may come closer, never closer than half the query.
    starts = sorted(h.start for h in search(index, encoder, cut, top_k=10, per_track=10, overlap=0.5)
                    if h.path == "long")  # fmt: skip
    assert len(starts) > 3 and all(b - a >= 32 - 8 for a, b in itertools.pairwise(starts))


def test_scaling_a_track_hardly_changes_the_ranking(encoder, tracks, index):
    query = tracks[1].frames(29, 93)
    centre = np.nanmean(query.joints.reshape(-1, 2), axis=0)
    for factor in (0.7, 1.3):
        scaled = query.replace(joints=(query.joints - centre) * factor + centre)
        plain = search(index, encoder, query, top_k=4)
        other = search(index, encoder, scaled, top_k=4)
        assert other[0].path == plain[0].path == "t1" and other[0].start == pytest.approx(29, abs=2)
        assert other[0].score > 0.8
        assert [h.path for h in other] == [h.path for h in plain]


def test_long_queries_search_fewer_phases_then_refine(encoder):
    from retarget.applications.search.query import KERNEL_BUDGET, _coarse_rows

    long = [moving_figure(seed, frames=480) for seed in (5, 6)]
    index = from_sequences([track_features(encoder, t) for t in long], ["a", "b"], [30.0] * 2, [480] * 2, encoder)
    query = long[1].frames(101, 301)  # 200 frames: 24 code steps, 2 phases fit the budget
    features, phases = query_features(encoder, query)
    assert len(phases) == 8 and len(_coarse_rows(phases, features.shape[-1], None)) * 24 <= KERNEL_BUDGET
    quick = search(index, encoder, query, top_k=2)
    exhaustive = search(index, encoder, query, top_k=2, phase_step=1)
    assert quick[0].path == "b" and quick[0].start == 101
    assert [(h.path, h.start) for h in quick] == [(h.path, h.start) for h in exhaustive]
    assert quick[0].score == pytest.approx(exhaustive[0].score, abs=1e-5)


def test_track_filter(encoder, tracks, index):
    hits = search(index, encoder, tracks[2].frames(40, 104), top_k=4, tracks=np.array([True, True, False, True]))
    assert "t2" not in [h.path for h in hits] and len(hits) == 3
    with pytest.raises(ValueError, match="tracks must be"):
        search(index, encoder, tracks[2].frames(40, 104), tracks=np.array([True, False]))


def test_short_queries(encoder, tracks, index):
    # 20 frames: too short for the 8 phases of the code grid, long enough for the first few.
    hits = search(index, encoder, tracks[0].frames(50, 70), top_k=1)
    assert hits[0].path == "t0" and hits[0].end - hits[0].start == 20
    with pytest.raises(InputError, match="needs at least 16"):
        search(index, encoder, tracks[0].frames(50, 65))


def test_raw_joint_baseline_runs_the_same_search(tracks):
    encoder = JointEncoder()
    sequences = [track_features(encoder, t) for t in tracks]
    assert sequences[0].shape == (28, FRAMES)
    index = from_sequences(sequences, [f"t{k}" for k in range(4)], [30.0] * 4, [FRAMES] * 4, encoder)
    hits = search(index, encoder, tracks[3].frames(21, 85), top_k=2)
    assert hits[0].path == "t3" and hits[0].start == 21 and hits[0].score > 0.99


def test_an_index_answers_only_its_own_encoder(index, tracks):
    with pytest.raises(InputError, match="rebuild the index or pass the same --weights"):
        search(index, JointEncoder(), tracks[0].frames(0, 64))


def test_match_to_dict_is_json(encoder, tracks, index):
    hit = search(index, encoder, tracks[0].frames(8, 72), top_k=1)[0]
    assert hit.path == "t0" and abs(hit.start - 8) <= 1 and hit.end - hit.start == 64
    assert json.loads(json.dumps(hit.to_dict())) == {"path": "t0", "track": 0, "start": hit.start, "end": hit.end,
                                                      "score": pytest.approx(hit.score)}  # fmt: skip
