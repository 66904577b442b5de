import json
import math

import numpy as np
import pytest
from hypothesis import event, given
from hypothesis import strategies as st

from pose_io import BODY25, COCO17, COCO18, InputError, read_detections, read_track, read_track_summary
from pose_io.frame_bounds import infer_image_size
from pose_io.readers import detect_format, parse_size
from tests.pose_io.fuzzing import fast_and_slow
from tests.pose_io.test_fuzz_tables import assert_sane


def person_values(n_joints: int, offset: float = 100.0, conf: float = 0.8, seed: int = 0) -> list[float]:
    """Flat [x, y, c] * J keypoints of a plausible figure around ``offset``."""
    rng = np.random.default_rng(seed)
    xy = offset + rng.uniform(0, 80, (n_joints, 2))
    return np.concatenate([xy, np.full((n_joints, 1), conf)], axis=1).ravel().tolist()


def write_frame(folder, number: int, people: list[list[float]], stem: str = "clip", digits: int = 12) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    data = {"version": 1.3, "people": [{"pose_keypoints_2d": p} for p in people]}
    (folder / f"{stem}_{number:0{digits}d}_keypoints.json").write_text(json.dumps(data))


# ----------------------------------------------------------------------------------------------- OpenPose


def test_frames_are_ordered_by_number_not_by_name(tmp_path):
    folder = tmp_path / "poses"
    for n in (0, 1, 2, 10):
        values = person_values(25)
        values[0] = float(n)  # nose x tells the frame apart
        write_frame(folder, n, [values], digits=1)  # clip_10_ sorts before clip_2_ as a string
    track = read_track(folder)
    assert track.num_frames == 11
    assert track.joint("nose")[[0, 1, 2, 10], 0].tolist() == [0.0, 1.0, 2.0, 10.0]
    assert track.missing[3:10].all(), "frame numbers missing from the run are all-missing frames"


def test_zero_confidence_is_missing_and_layout_from_count(tmp_path):
    values = person_values(18)
    values[3 * COCO18.index("l_wrist") + 2] = 0.0
    write_frame(tmp_path / "p", 0, [values])
    track = read_track(tmp_path / "p")
    assert track.layout == "coco18"
    j = COCO18.index("l_wrist")
    assert np.isnan(track.joints[0, j]).all() and track.confidence[0, j] == 0.0


def test_shared_examples(shared_dir):
    tall = read_track(shared_dir / "openpose_examples" / "tall_man")
    assert tall.num_frames == 135 and tall.layout == "body25" and tall.fps == 30.0
    small = read_track(shared_dir / "openpose_examples" / "small_man", image_size=(720, 720))
    assert small.num_frames == 121 and small.image_size == (720, 720)
    j = BODY25.index("l_wrist")
    assert np.isnan(small.joints[37, j]).all() and small.confidence[37, j] == 0.0
    assert not small.missing[36, j] and not small.missing[38, j]
    raw = json.loads((shared_dir / "openpose_examples" / "small_man" / "small_man_000000000000_keypoints.json")
                     .read_text())["people"][0]["pose_keypoints_2d"]
    np.testing.assert_array_equal(small.joints[0, 0], np.float32(raw[:2]))


def test_image_size_inferred_as_multiple_of_16(tmp_path):
    values = person_values(25, offset=600.0)  # joints in [600, 680)
    values[0], values[1] = 700.0, 610.0  # the nose sets the width (a joint 8 bodies away would be an outlier)
    write_frame(tmp_path / "p", 0, [values])
    summary = read_track_summary(tmp_path / "p")
    w, h = summary.track.image_size
    assert w == 704 and w % 16 == 0 and h % 16 == 0
    assert summary.size_source == "inferred" and summary.fps_source == "default"
    assert read_track(tmp_path / "p", image_size=(1280, 720), fps=25).image_size == (1280, 720)
    assert read_track_summary(tmp_path / "p", fallback_size=(800, 600)).track.image_size == (800, 600)


@pytest.mark.parametrize(
    "setup, message",
    [
        (lambda d: None, "empty"),
        (lambda d: (d / "notes.txt").write_text("x"), "no \\*_keypoints.json"),
        (lambda d: (d / "a_000_keypoints.json").write_text("{not json"), "not valid JSON"),
        (lambda d: (d / "a_000_keypoints.json").write_bytes(b"\xff\xfe\x00"), "not valid JSON"),
        (lambda d: (d / "a_000_keypoints.json").write_text("[1, 2]"), "people"),
        (lambda d: write_frame(d, 0, [[1.0, 2.0, 0.5] * 20]), "60 keypoint values"),
        (lambda d: write_frame(d, 0, []), "no person in any frame"),
        (lambda d: write_frame(d, 0, [[0.0] * 75]), "no person in any frame"),
        (lambda d: write_frame(d, 0, [[-5.0, 2.0, 0.5] + person_values(24)]), "negative coordinates"),
        (lambda d: (d / "a_000_keypoints.json").write_text(
            '{"people":[{"pose_keypoints_2d":[NaN' + ",1" * 74 + "]}]}"), "non-finite"),
        (lambda d: write_frame(d, 0, [[1.0, 2.0, 1.5] * 25]), "confidence outside"),
        (lambda d: write_frame(d, 0, [["a"] * 75]), "list of numbers"),
        (lambda d: (write_frame(d, 0, [person_values(25)]), write_frame(d, 1, [person_values(18)])),
         "other frames have"),
        (lambda d: (write_frame(d, 0, [person_values(25)]), write_frame(d, 0, [person_values(25)], stem="b")),
         "two files for frame 0"),
        (lambda d: (write_frame(d, 0, [person_values(25)]), write_frame(d, 10**9, [person_values(25)])),
         "numbers run from"),
    ],
)
def test_bad_openpose_folders(tmp_path, setup, message):
    folder = tmp_path / "poses"
    folder.mkdir()
    setup(folder)
    with pytest.raises(InputError, match=message) as info:
        read_track(folder)
    assert "\n" not in str(info.value)


def test_missing_path_and_unknown_suffix(tmp_path):
    with pytest.raises(InputError, match="does not exist"):
        read_track(tmp_path / "nope")
    (tmp_path / "a.txt").write_text("x")
    with pytest.raises(InputError, match="unknown pose file type"):
        read_track(tmp_path / "a.txt")
    with pytest.raises(InputError, match="unknown pose format"):
        read_track(tmp_path, fmt="bvh")


# random JSON values: a track or an InputError, nothing else
_json = st.recursive(
    st.none() | st.booleans() | st.integers(-10**6, 10**20) | st.floats(allow_nan=False, allow_infinity=False)
    | st.text(max_size=5),
    lambda children: st.lists(children, max_size=6) | st.dictionaries(st.text(max_size=8), children, max_size=4),
    max_leaves=30,
)
_triple = st.tuples(st.floats(-2, 1000) | st.integers(0, 3000), st.floats(-2, 1000),
                    st.sampled_from([0.0, 0.5, 1.0]) | st.floats(0, 1.2))
_well_formed = st.sampled_from([15, 17, 18, 25, 33]).flatmap(
    lambda n: st.lists(_triple, min_size=n, max_size=n)).map(lambda ts: [v for t in ts for v in t])
_HOSTILE_VALUES = [1e6, -1e6, 1e30, 1e38, 1e39, 1e308, 10**400, 2e4, -0.5, 1.5]


@st.composite
def _with_hostile_value(draw, values: list) -> list:
    """A keypoint list with one value replaced by a hostile number (huge, beyond float32, negative)."""
    values = list(values)
    if values:
        values[draw(st.integers(0, len(values) - 1))] = draw(st.sampled_from(_HOSTILE_VALUES))
    return values


_keypoints = (_well_formed | _well_formed.flatmap(_with_hostile_value)
              | st.lists(st.floats(-10, 2000) | st.integers(-3, 3000), max_size=80))
_person = st.fixed_dictionaries({"pose_keypoints_2d": _keypoints}) | _json
_frame = st.fixed_dictionaries({"version": st.just(1.3), "people": st.lists(_person, max_size=3)}) | _json
_sidecar = st.fixed_dictionaries({
    "kind": st.sampled_from(["clone2d-openpose-folder", "other"]),
    "fps": st.sampled_from([30, 25.0, 0, -1, 1e9, 1000, 1001, 10**400, "30", None, True]),
    "image_size": st.sampled_from([[640, 480], [0, 1], [100000, 100000], [16384, 16384], [640.5, 480], "640x480",
                                   [1e308, 1], [640], None]),
    "layout": st.sampled_from(["body25", "coco18", "nope", 5]),
}) | _json


def _openpose_case(tmp_path_factory, frames, raw, sidecar):
    folder = tmp_path_factory.mktemp("fuzz")
    for number, frame in frames:
        (folder / f"f_{number}_keypoints.json").write_text(json.dumps(frame))
    if raw:
        (folder / "f_99_keypoints.json").write_bytes(raw)
    if sidecar is not None:
        (folder / "clone2d_track.json").write_text(json.dumps(sidecar))
    try:
        track = read_track(folder)
    except InputError as exc:
        assert "\n" not in str(exc)
        event("InputError")
        return
    event("track")
    assert track.joints.shape[1] in (15, 17, 18, 25, 33)
    assert_sane(track)


test_openpose_reader_never_crashes, test_openpose_reader_never_crashes_slow = fast_and_slow(
    lambda: given(frames=st.lists(st.tuples(st.integers(0, 40), _frame), min_size=1, max_size=5),
                  raw=st.just(b"") | st.binary(max_size=20), sidecar=st.none() | _sidecar)(_openpose_case), fast=60)


def _results_case(tmp_path_factory, entries):
    path = tmp_path_factory.mktemp("fuzz") / "results.json"
    path.write_text(json.dumps(entries))
    try:
        assert_sane(read_track(path))
        event("track")
    except InputError as exc:
        assert "\n" not in str(exc)
        event("InputError")


test_results_reader_never_crashes, test_results_reader_never_crashes_slow = fast_and_slow(
    lambda: given(entries=st.lists(st.fixed_dictionaries(
        {"image_id": st.integers(0, 30) | st.text(max_size=6) | st.just("9" * 5000 + ".jpg"), "keypoints": _keypoints})
        | _json, max_size=6))(_results_case), fast=40)


# ----------------------------------------------------------------------------------------------- COCO / AlphaPose


def coco_entry(image_id, offset=100.0, score=0.9, **extra):
    return {"image_id": image_id, "category_id": 1, "keypoints": person_values(17, offset, 0.9), "score": score,
            **extra}


def test_coco_results(tmp_path):
    entries = [coco_entry(0), coco_entry(2, offset=104.0), coco_entry(1, offset=102.0),
               {"image_id": 1, "category_id": 3, "keypoints": [0.0] * 51, "score": 1.0}]
    entries[0]["keypoints"][2] = 2  # a COCO visibility flag counts as confidence 1
    path = tmp_path / "res.json"
    path.write_text(json.dumps(entries))
    assert detect_format(path) == "coco"
    track = read_track(path)
    assert track.layout == "coco17" and track.num_frames == 3
    assert track.confidence[0, 0] == 1.0
    np.testing.assert_allclose(track.joint("nose")[:, 0] - track.joint("nose")[0, 0], [0, 2, 4], atol=1e-4)


def test_alphapose_follows_idx(tmp_path):
    # Two people; the followed one (idx 7, the larger) jumps far between frames: its idx keeps it.
    small = [coco_entry(f"{t}.jpg", offset=300.0, idx=[3]) for t in range(3)]
    big = [coco_entry(f"{t}.jpg", offset=10.0 + 200 * t, idx=7) for t in range(3)]
    for e in big:
        e["keypoints"] = (np.array(e["keypoints"]).reshape(17, 3) * [2, 2, 1]).ravel().tolist()
    path = tmp_path / "alpha.json"
    path.write_text(json.dumps(small + big))
    assert detect_format(path) == "alphapose"
    det = read_detections(path)
    assert det.ids is not None and det.counts.tolist() == [2, 2, 2]
    track = read_track(path)
    starts = track.joint("nose")[:, 0]
    assert np.all(np.diff(starts) > 300)


@pytest.mark.parametrize(
    "entries, message",
    [
        ({"a": 1}, "results list"),
        ([{"image_id": 0}], "needs image_id and keypoints"),
        ([{"image_id": -1, "keypoints": [1.0] * 51}], "non-negative integer"),
        ([{"image_id": "x.jpg", "keypoints": [1.0] * 51}], "no frame number"),
        ([{"image_id": 0, "keypoints": [1.0] * 50}], "50 keypoint values"),
        ([{"image_id": 0, "keypoints": [1.0, 1.0, -1.0] * 17}], "negative keypoint confidence"),
        ([{"image_id": 0, "category_id": 2, "keypoints": [1.0] * 51}], "no person detections"),
    ],
)
def test_bad_results_files(tmp_path, entries, message):
    path = tmp_path / "r.json"
    path.write_text(json.dumps(entries))
    with pytest.raises(InputError, match=message):
        read_track(path, fmt="alphapose" if entries and isinstance(entries, list)
                   and isinstance(entries[0].get("image_id"), str) else "coco")


def test_single_openpose_frame_file_points_to_folder(tmp_path):
    write_frame(tmp_path, 0, [person_values(25)])
    with pytest.raises(InputError, match="pass the folder"):
        read_track(next(tmp_path.glob("*.json")))


# ----------------------------------------------------------------------------------------------- arrays, CSV


@pytest.mark.parametrize("n_joints, layout", [(25, "body25"), (15, "body15"), (18, "coco18"), (17, "coco17"),
                                              (33, "mediapipe33")])
def test_npy_layout_from_joint_count(tmp_path, n_joints, layout):
    arr = np.random.default_rng(0).uniform(0.1, 1.0, (4, n_joints, 3)).astype(np.float32)
    arr[..., :2] *= 100
    arr[1, 0, :2] = np.nan
    np.save(tmp_path / "a.npy", arr)
    track = read_track(tmp_path / "a.npy")
    assert track.layout == layout and track.missing[1, 0] and track.missing.sum() == 1
    np.testing.assert_array_equal(track.confidence[0], arr[0, :, 2])
    np.save(tmp_path / "b.npy", arr[..., :2])
    assert (read_track(tmp_path / "b.npy").confidence[0] == 1.0).all()


def test_bad_arrays(tmp_path):
    np.save(tmp_path / "a.npy", np.zeros((3, 20, 2)))
    with pytest.raises(InputError, match="20 joints"):
        read_track(tmp_path / "a.npy")
    np.save(tmp_path / "b.npy", np.zeros((3, 25)))
    with pytest.raises(InputError, match="3-D numeric"):
        read_track(tmp_path / "b.npy")
    (tmp_path / "c.npy").write_bytes(b"garbage")
    with pytest.raises(InputError, match="cannot read"):
        read_track(tmp_path / "c.npy")
    np.savez(tmp_path / "d.npz", joints=np.zeros((2, 25, 2)))
    with pytest.raises(InputError, match="lacks confidence"):
        read_track(tmp_path / "d.npz")
    np.savez(tmp_path / "e.npz", joints=np.ones((2, 25, 2)), confidence=np.ones((2, 25)), layout="coco18")
    with pytest.raises(InputError, match="does not fit"):
        read_track(tmp_path / "e.npz")


def test_csv_reads_documented_format(tmp_path):
    names = COCO17.joints
    header = "frame," + ",".join(f"{n}_x,{n}_y" for n in names)  # no _c columns: confidence 1
    rows = ["0," + ",".join(["10.5,20"] * 17), "2," + ",".join([",", *["1,2"] * 16])]
    (tmp_path / "a.csv").write_text("# fps: 25\n# image_size: 64x48\n" + "\n".join([header, *rows]) + "\n")
    track = read_track(tmp_path / "a.csv")
    assert track.layout == "coco17" and track.fps == 25.0 and track.image_size == (64, 48)
    assert track.num_frames == 3 and track.missing[1].all() and track.missing[2, 0] and not track.missing[2, 1]
    assert track.joints[0, 3].tolist() == [10.5, 20.0]


@pytest.mark.parametrize(
    "text, message",
    [
        ("frame,nose_x\n0,1\n", "do not name the joints"),
        ("t,nose_x\n0,1\n", "first column"),
        ("frame\n", "header line and at least one"),
        ("frame," + ",".join(f"{n}_x,{n}_y" for n in COCO17.joints) + "\n0,a" + ",1" * 33 + "\n", "non-numeric"),
        ("# fps: -3\nframe," + ",".join(f"{n}_x,{n}_y" for n in COCO17.joints) + "\n0" + ",1" * 34 + "\n", "fps"),
    ],
)
def test_bad_csv(tmp_path, text, message):
    (tmp_path / "a.csv").write_text(text)
    with pytest.raises(InputError, match=message):
        read_track(tmp_path / "a.csv")


def test_parse_size_and_infer():
    assert parse_size("640x480") == (640, 480)
    for bad in ("640", "0x3", "axb"):
        with pytest.raises(InputError):
            parse_size(bad)


def test_infer_image_size_ignores_missing(tmp_path):
    arr = np.full((2, 25, 3), np.nan, dtype=np.float32)
    arr[0, 0] = (15.0, 16.0, 1.0)
    np.save(tmp_path / "a.npy", arr)
    assert infer_image_size(read_detections(tmp_path / "a.npy")) == (16, 32)
    assert math.isclose(read_track(tmp_path / "a.npy").fps, 30.0)
