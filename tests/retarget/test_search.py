"""Motion retrieval: the index and its file, the one-pass search, its hits, and the evaluation's plumbing."""

from __future__ import annotations

import itertools
import json
import zipfile
from pathlib import Path

import numpy as np
import pytest
import torch

from pose_io.errors import InputError
from pose_io.resample import resample
from pose_io.track import PoseTrack
from pose_io.writers import write_track
from retarget.api import load_retargeter
from retarget.search import (
    JointEncoder,
    MotionCodeEncoder,
    SearchIndex,
    build_index,
    correlate,
    find_tracks,
    from_sequences,
    load_index,
    save_index,
    search,
)
from retarget.search.features import query_features, track_features
from tests.figures import walking_figure

FRAMES = 160


def moving_figure(seed: int, frames: int = FRAMES, **figure: object) -> PoseTrack:
    """A walking figure whose joints also wander smoothly at random: a motion that never repeats itself."""
    base = walking_figure(frames, seed=seed, **figure)
    rng = np.random.default_rng(100 + seed)
    noise = rng.normal(0.0, 1.0, base.joints.shape)
    kernel = np.exp(-0.5 * (np.arange(-12, 13) / 5.0) ** 2)
    for j in range(noise.shape[1]):
        for c in range(2):
            noise[:, j, c] = np.convolve(noise[:, j, c], kernel / kernel.sum() * 6, mode="same")
    return base.replace(joints=base.joints + 25.0 * noise.astype(np.float32))


@pytest.fixture(scope="module")
def encoder() -> MotionCodeEncoder:
    return MotionCodeEncoder(load_retargeter(None, "cpu"))


@pytest.fixture(scope="module")
def tracks() -> list[PoseTrack]:
    return [moving_figure(seed) for seed in range(4)]


@pytest.fixture(scope="module")
def index(encoder: MotionCodeEncoder, tracks: list[PoseTrack]) -> SearchIndex:
    sequences = [track_features(encoder, t) for t in tracks]
    return from_sequences(sequences, [f"t{k}" for k in range(len(tracks))], [t.fps for t in tracks],
                          [len(t) for t in tracks], encoder)


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
    from retarget.search.query import KERNEL_BUDGET, _coarse_rows

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


# --------------------------------------------------------------------------------------- files and folders


def _write_collection(root: Path, tracks: list[PoseTrack]) -> None:
    write_track(tracks[0], root / "a" / "first.npz")
    write_track(tracks[1], root / "a" / "b" / "second")  # an OpenPose folder: one track, its frames not walked
    write_track(tracks[2], root / "third.csv")
    (root / "a" / "notes.json").write_text("{}")  # found in a folder, unreadable: skipped
    (root / "a" / ".hidden.npz").write_bytes(b"junk")  # hidden: not even looked at


def test_index_round_trip(encoder, tracks, tmp_path):
    _write_collection(tmp_path / "tracks", tracks)
    found = find_tracks([tmp_path / "tracks"])
    names = sorted(p.name for p, _ in found)
    assert names == ["first.npz", "notes.json", "second", "third.csv"]
    assert not any(named for _, named in found)
    again = find_tracks([tmp_path / "tracks" / "third.csv", tmp_path / "tracks"])  # reached twice: listed once
    assert (again[0][0].name, again[0][1]) == ("third.csv", True) and len(again) == 4
    calls = []
    index, skipped = build_index([tmp_path / "tracks"], encoder, progress=lambda d, t, p: calls.append((d, t)))
    assert [Path(s.path).name for s in skipped] == ["notes.json"]
    assert calls[-1] == (4, 4)
    assert sorted(Path(p).name for p in index.paths) == ["first.npz", "second", "third.csv"]
    assert list(index.frames) == [FRAMES] * 3 and list(index.track_fps) == [30.0] * 3

    path = save_index(index, tmp_path / "collection.index")
    assert path.is_file() and not list(tmp_path.glob(".collection*"))  # one file, no temporary left
    with pytest.raises(InputError, match="already exists"):
        save_index(index, path)
    loaded = load_index(path)
    assert loaded.paths == index.paths and (loaded.kind, loaded.digest, loaded.stride) == ("motion", encoder.digest, 8)
    assert np.array_equal(loaded.offsets, index.offsets) and np.array_equal(loaded.frames, index.frames)
    assert torch.allclose(loaded.features, index.features, atol=2e-2, rtol=1e-3)  # float16 on disk
    query = tracks[1].frames(16, 80)
    a, b = search(index, encoder, query, top_k=3), search(loaded, encoder, query, top_k=3)
    assert [(h.path, h.start, h.end) for h in a] == [(h.path, h.start, h.end) for h in b]
    assert [h.score for h in a] == pytest.approx([h.score for h in b], abs=1e-3)


def test_a_named_unreadable_track_is_an_error(encoder, tmp_path):
    (tmp_path / "bad.json").write_text("[1, 2")
    with pytest.raises(InputError, match="bad.json"):
        build_index([tmp_path / "bad.json"], encoder)
    with pytest.raises(InputError, match="no such file"):
        build_index([tmp_path / "missing"], encoder)
    with pytest.raises(InputError, match="no readable pose tracks"):
        build_index([tmp_path], encoder)  # only the unreadable one, found in a folder
    write_track(walking_figure(10), tmp_path / "short.npz")
    with pytest.raises(InputError, match="at least 16"):
        build_index([tmp_path / "short.npz"], encoder)


def _rewrite(path: Path, out: Path, **changes: object) -> Path:
    with np.load(path, allow_pickle=False) as data:
        arrays = {k: data[k] for k in data.files}
    arrays.update(changes)
    for key in [k for k, v in changes.items() if v is None]:
        del arrays[key]
    with open(out, "wb") as f:
        np.savez(f, **arrays)
    return out


def test_bad_index_files_are_input_errors(encoder, index, tmp_path):
    good = save_index(index, tmp_path / "good.npz")
    cases = {
        "missing": (tmp_path / "nope.npz", "no such search index"),
        "text": (tmp_path / "text.npz", "not a readable search index"),
        "truncated": (tmp_path / "cut.npz", "not a readable search index"),
        "other npz": (tmp_path / "other.npz", "not a clone2d search index"),
        "newer": (_rewrite(good, tmp_path / "newer.npz", version=np.array(99)), "version 99; this clone2d reads up"),
        "no features": (_rewrite(good, tmp_path / "nofeat.npz", features=None), "damaged search index"),
        "bad offsets": (_rewrite(good, tmp_path / "offsets.npz", offsets=np.array([0, 5, 3, 60, 80])), "damaged"),
        "nan": (_rewrite(good, tmp_path / "nan.npz", features=np.full((128, 80), np.nan, np.float16)), "damaged"),
    }
    (tmp_path / "text.npz").write_text("hello")
    (tmp_path / "cut.npz").write_bytes(good.read_bytes()[:500])
    np.savez(tmp_path / "other.npz", joints=np.zeros((3, 15, 2)))
    for name, (path, message) in cases.items():
        with pytest.raises(InputError, match=message):
            load_index(path)
        assert name  # for the failure report
    assert zipfile.is_zipfile(good)


def test_an_index_answers_only_its_own_encoder(index, tracks):
    with pytest.raises(InputError, match="rebuild the index or pass the same --weights"):
        search(index, JointEncoder(), tracks[0].frames(0, 64))


def test_match_to_dict_is_json(encoder, tracks, index):
    hit = search(index, encoder, tracks[0].frames(8, 72), top_k=1)[0]
    assert hit.path == "t0" and abs(hit.start - 8) <= 1 and hit.end - hit.start == 64
    assert json.loads(json.dumps(hit.to_dict())) == {"path": "t0", "track": 0, "start": hit.start, "end": hit.end,
                                                      "score": pytest.approx(hit.score)}  # fmt: skip


# --------------------------------------------------------------------------------------- evaluation


@pytest.fixture(scope="module")
def tiny_world(tmp_path_factory: pytest.TempPathFactory):
    """A motion world of four humanoid clips written here (see tests/retarget/world/humanoid.py)."""
    from retarget.world import MotionWorld
    from tests.retarget.world.humanoid import write_clip

    root = tmp_path_factory.mktemp("mocap")
    (root / "bandai").mkdir()
    for name in ("walk_normal_001", "bow_normal_001", "run_normal_001", "walk_fast_001"):
        write_clip(root / "bandai" / f"dataset-1_{name}.bvh.gz")
    return MotionWorld.build(root, tmp_path_factory.mktemp("cache"), n_train_characters=2, n_val_characters=2,
                             n_test_characters=2)  # fmt: skip


def test_retrieval_evaluation_on_a_tiny_world(encoder, tiny_world):
    from retarget.search.evaluate import RetrievalEvalConfig, evaluate_retrieval, markdown_table

    split = tiny_world.split("test")
    calls = []
    config = RetrievalEvalConfig(queries=4, seed=3)
    doc = evaluate_retrieval(split, encoder, config, fps=tiny_world.config.fps,
                             progress=lambda done, total: calls.append((done, total)))  # fmt: skip
    assert calls[-1] == (8, 8)  # both methods
    assert doc["queries"] == 4 and doc["tracks"] == doc["clips"] * 4 and doc["split"] == "test"
    assert set(doc["methods"]) == {"motion", "joints"}
    for m in doc["methods"].values():
        assert 0.0 <= m["top1"] <= m["topk"] <= 1.0
        assert m["localised"] <= 4 and sum(m["queries_by_view_gap"].values()) == 4
    # One clip in the test split: every hit is the query's motion, and the same seed gives the same numbers.
    if doc["clips"] == 1:
        assert doc["methods"]["motion"]["top1"] == 1.0
    again = evaluate_retrieval(split, encoder, config, fps=tiny_world.config.fps)["methods"]
    for name, m in doc["methods"].items():
        assert {k: v for k, v in again[name].items() if k != "seconds_per_query"} == {
            k: v for k, v in m.items() if k != "seconds_per_query"}
    table = markdown_table(doc)
    assert "motion codes (ours)" in table and "raw joints" in table and "top-5" in table
    with pytest.raises(ValueError):
        RetrievalEvalConfig(pairs_per_clip=2)
