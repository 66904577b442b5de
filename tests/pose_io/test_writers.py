import json

import numpy as np
import pytest

from pose_io import InputError, PoseTrack, read_track, write_track
from pose_io.read_json import SIDECAR_NAME


def ragged_track(layout: str = "body25", n_joints: int = 25) -> PoseTrack:
    """Awkward values: leading/trailing empty frames, missing joints, float32 noise, odd fps."""
    rng = np.random.default_rng(3)
    joints = rng.uniform(0, 500, (12, n_joints, 2)).astype(np.float32)
    conf = rng.uniform(0.01, 1.0, (12, n_joints)).astype(np.float32)
    conf[0] = 0.0  # all-missing first and last frames
    conf[-1] = 0.0
    conf[4, :3] = 0.0
    joints[6, 5] = np.nan
    joints[7, 2] = (0.0, 0.0)  # a real joint at the origin is not "missing"
    return PoseTrack(joints, conf, 29.97, (640, 360), layout)


@pytest.mark.parametrize("name", ["poses", "poses.npz", "poses.csv"])
@pytest.mark.parametrize("layout, n", [("body25", 25), ("body15", 15), ("coco17", 17), ("mediapipe33", 33)])
def test_write_read_round_trip_is_identical(tmp_path, name, layout, n):
    track = ragged_track(layout, n)
    path = write_track(track, tmp_path / name)
    back = read_track(path)
    assert back.equals(track), name
    np.testing.assert_array_equal(back.joints, track.joints)  # bit for bit, NaN where missing
    np.testing.assert_array_equal(back.confidence, track.confidence)
    assert back.fps == track.fps and back.image_size == track.image_size and back.layout == track.layout


def test_shared_example_round_trip(shared_dir, tmp_path):
    track = read_track(shared_dir / "openpose_examples" / "small_man", image_size=(720, 720))
    for name in ("small_man", "small_man.npz", "small_man.csv"):
        assert read_track(write_track(track, tmp_path / name)).equals(track)


def test_openpose_folder_layout(tmp_path):
    track = ragged_track()
    write_track(track, tmp_path / "clip")
    names = sorted(p.name for p in (tmp_path / "clip").iterdir())
    assert names[0] == "clip_000000000000_keypoints.json" and SIDECAR_NAME in names and len(names) == 13
    frame4 = json.loads((tmp_path / "clip" / "clip_000000000004_keypoints.json").read_text())
    assert frame4["version"] == 1.3 and len(frame4["people"][0]["pose_keypoints_2d"]) == 75
    assert frame4["people"][0]["pose_keypoints_2d"][:9] == [0] * 9  # missing joints are 0, 0, 0
    assert json.loads((tmp_path / "clip" / "clip_000000000000_keypoints.json").read_text())["people"] == []
    sidecar = json.loads((tmp_path / "clip" / SIDECAR_NAME).read_text())
    assert sidecar["fps"] == 29.97 and sidecar["image_size"] == [640, 360] and sidecar["frames"] == 12


def test_without_sidecar_the_folder_still_reads_like_openpose(tmp_path, walking_track):
    write_track(walking_track, tmp_path / "clip")
    (tmp_path / "clip" / SIDECAR_NAME).unlink()
    back = read_track(tmp_path / "clip", image_size=(640, 480))
    assert back.equals(walking_track)


def test_existing_output_is_kept_unless_overwrite(tmp_path, walking_track):
    path = write_track(walking_track, tmp_path / "a.npz")
    before = path.read_bytes()
    with pytest.raises(InputError, match="already exists"):
        write_track(walking_track.frames(0, 5), path)
    assert path.read_bytes() == before
    write_track(walking_track.frames(0, 5), path, overwrite=True)
    assert read_track(path).num_frames == 5
    write_track(walking_track, tmp_path / "dir")
    write_track(walking_track.frames(0, 3), tmp_path / "dir", overwrite=True)
    assert len(list((tmp_path / "dir").glob("*_keypoints.json"))) == 3


def test_negative_coordinates_refused_for_openpose_and_nothing_written(tmp_path, walking_track):
    joints = walking_track.joints.copy()
    joints[3, 4, 0] = -2.0
    track = walking_track.replace(joints=joints)
    with pytest.raises(InputError, match="negative coordinates .*r_wrist at frame 3"):
        write_track(track, tmp_path / "out")
    assert list(tmp_path.iterdir()) == []
    assert read_track(write_track(track, tmp_path / "out.npz")).equals(track)


@pytest.mark.parametrize("name", ["a.npz", "a.csv", "folder"])
def test_a_track_without_a_visible_joint_is_not_written(tmp_path, walking_track, name):
    empty = walking_track.replace(joints=np.full_like(walking_track.joints, np.nan),
                                  confidence=np.zeros_like(walking_track.confidence))
    with pytest.raises(InputError, match="nothing to write: no frame of the track shows a joint"):
        write_track(empty, tmp_path / name)  # no reader would take it back ("no person in any frame")
    assert list(tmp_path.iterdir()) == []


def test_unknown_output_types(tmp_path, walking_track):
    with pytest.raises(InputError, match="cannot write pose files of type .json"):
        write_track(walking_track, tmp_path / "a.json")
    with pytest.raises(InputError, match="unknown output pose format"):
        write_track(walking_track, tmp_path / "a", fmt="bvh")
    assert list(tmp_path.iterdir()) == []


# ----------------------------------------------------------------------------------------------- linear in length


def long_track(frames: int, layout: str = "body15") -> PoseTrack:
    """``frames`` frames of random joints with some missing, in ``layout``."""
    from pose_io.layouts import get_layout

    n = len(get_layout(layout))
    rng = np.random.default_rng(frames)
    joints = rng.uniform(0, 600, (frames, n, 2)).astype(np.float32)
    conf = rng.uniform(0.1, 1.0, (frames, n)).astype(np.float32)
    conf[::7, 3] = 0.0
    return PoseTrack(joints, conf, 30.0, (640, 480), layout)


def count_missing_calls(monkeypatch) -> list[int]:
    """Count reads of ``PoseTrack.missing`` (it computes a [T, J] mask on every read)."""
    calls = [0]
    original = PoseTrack.missing.fget

    def missing(self: PoseTrack) -> np.ndarray:
        calls[0] += 1
        return original(self)

    monkeypatch.setattr(PoseTrack, "missing", property(missing))
    return calls


@pytest.mark.parametrize("name", ["poses", "poses.npz", "poses.csv"])
def test_writers_compute_the_missing_mask_once_not_per_cell(tmp_path, monkeypatch, name):
    track = long_track(500)
    calls = count_missing_calls(monkeypatch)
    write_track(track, tmp_path / name)
    # At most twice (write_track's check for a track with no visible joint, and the writer's own), never per cell.
    assert calls[0] <= 2, f"{name}: PoseTrack.missing read {calls[0]} times for {track.num_frames} frames"


def test_100k_frame_npz_converts_to_csv(tmp_path, monkeypatch):
    """The tester's case (`clone pose convert` of 100,000 frames to CSV never finished): linear now.

    The proxy for "linear": the CSV writer reads the [T, J] missing mask a constant number of times; it
    used to read it once per cell (T * J times, each O(T * J)). Speed itself is measured in bench/io.py.
    """
    from typer.testing import CliRunner

    from clone.cli.main import app

    track = long_track(100_000)
    write_track(track, tmp_path / "long.npz")
    calls = count_missing_calls(monkeypatch)
    result = CliRunner().invoke(app, ["pose", "convert", str(tmp_path / "long.npz"), str(tmp_path / "long.csv")])
    assert result.exit_code == 0, result.output
    assert calls[0] <= 3, calls[0]
    monkeypatch.undo()
    assert read_track(tmp_path / "long.csv").equals(track)


def _profiled_calls(fn) -> int:
    """Python and C function calls made by ``fn()``: a deterministic measure of work."""
    import sys

    count = [0]

    def profiler(frame, event, arg):
        if event in ("call", "c_call"):
            count[0] += 1

    sys.setprofile(profiler)
    try:
        fn()
    finally:
        sys.setprofile(None)
    return count[0]


@pytest.mark.parametrize("name, small", [("poses.csv", 1_000), ("poses.npz", 1_000), ("poses", 100)])
def test_write_and_read_work_grows_linearly(tmp_path, name, small):
    """Ten times the frames costs at most ~ten times the calls (a per-frame scan of the track would be ~100x)."""
    calls = []
    for frames in (small, 10 * small):
        track = long_track(frames)
        path = tmp_path / f"{frames}" / name
        calls.append(_profiled_calls(lambda track=track, path=path: read_track(write_track(track, path))))
    assert calls[1] <= 12 * calls[0], calls
