import json

import numpy as np
import pytest
from typer.testing import CliRunner

from clone.cli.main import app
from pose_io import read_track, write_track
from pose_io.video import read_frames
from pose_io.video_out import VideoWriter

runner = CliRunner()


def invoke(*args: str):
    return runner.invoke(app, [str(a) for a in args])


def test_info_shows_counts_and_missing_table(tmp_path, walking_track):
    joints = walking_track.joints.copy()
    joints[3:5, 4] = np.nan
    write_track(walking_track.replace(joints=joints), tmp_path / "poses")
    result = invoke("pose", "info", tmp_path / "poses")
    assert result.exit_code == 0, result.output
    out = result.output
    assert "40 (1.33 s)" in out and "640x480 (from the file)" in out and "body25 (25 joints)" in out
    assert "1 person: 40 frames" in out
    row = next(line for line in out.splitlines() if "r_wrist" in line)
    assert "2" in row and "5.0%" in row


def test_info_counts_the_outliers_it_read_as_missing(tmp_path, walking_track):
    folder = write_track(walking_track, tmp_path / "poses")
    assert "outliers   0 joints" in invoke("pose", "info", folder).output
    # Two joints of OpenPose's JSON far outside the 640x480 image and the body (a detector's stray points).
    for frame, joint in ((7, 4), (9, 11)):
        path = sorted(folder.glob("*_keypoints.json"))[frame]
        doc = json.loads(path.read_text())
        doc["people"][0]["pose_keypoints_2d"][3 * joint : 3 * joint + 2] = [3000.0, 2500.0]
        path.write_text(json.dumps(doc))
    result = invoke("pose", "info", folder)
    assert result.exit_code == 0, result.output
    assert "outliers   2 joints far outside the image and body, read as missing" in result.output


def test_info_on_a_plain_openpose_folder_with_size(tmp_path, walking_track):
    """OpenPose's own output (no clone2d sidecar): fps by default, the image size as given."""
    folder = write_track(walking_track.replace(fps=25.0), tmp_path / "openpose")
    (folder / "clone2d_track.json").unlink()
    result = invoke("pose", "info", folder, "--size", "720x720")
    assert result.exit_code == 0, result.output
    assert "40 (1.33 s)" in result.output and "720x720 (given)" in result.output
    assert "30 (default" in result.output


def test_info_people_per_frame(tmp_path):
    folder = tmp_path / "multi"
    folder.mkdir()
    rng = np.random.default_rng(0)
    for t, n in enumerate([0, 1, 2, 2]):
        people = [{"pose_keypoints_2d": np.c_[rng.uniform(100 + 300 * k, 200 + 300 * k, (25, 2)),
                                              np.full(25, 0.9)].ravel().tolist()} for k in range(n)]
        (folder / f"m_{t:012d}_keypoints.json").write_text(json.dumps({"people": people}))
    result = invoke("pose", "info", folder)
    assert result.exit_code == 0, result.output
    assert "0 people: 1 frame, 1 person: 1 frame, 2 people: 2 frames" in result.output
    assert "from frame 1" in result.output


@pytest.mark.parametrize(
    "args, message",
    [
        (["pose", "info", "{tmp}/missing"], "does not exist"),
        (["pose", "info", "{tmp}/empty"], "empty"),
        (["pose", "info", "{tmp}/empty", "--size", "12"], "WIDTHxHEIGHT"),
        (["pose", "convert", "{tmp}/empty", "{tmp}/out.npz"], "empty"),
        (["pose", "convert", "{tmp}/good", "{tmp}/out.npz", "--to-layout", "smpl"], "'smpl'; valid: body25"),
        (["pose", "show", "{tmp}/good", "--out", "{tmp}/out.mp4", "--frames", "{tmp}/bad.mp4"], "cannot read as a video"),
        (["pose", "extract", "{tmp}/bad.mp4", "--out", "{tmp}/outdir"], "bad.mp4"),
    ],
)
def test_bad_input_is_one_line_and_writes_nothing(tmp_path, walking_track, args, message):
    (tmp_path / "empty").mkdir()
    (tmp_path / "bad.mp4").write_text("garbage")
    write_track(walking_track, tmp_path / "good.npz")
    args = [a.replace("{tmp}", str(tmp_path)).replace("good", "good.npz") for a in args]
    before = sorted(p.name for p in tmp_path.iterdir())
    result = invoke(*args)
    assert result.exit_code == 2
    lines = [line for line in result.output.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: ") and message in lines[0], result.output
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_convert_that_resamples_every_person_away_is_one_error_and_writes_nothing(tmp_path):
    """Found by the 10,000-example fuzz: two frames at 30 fps, the person only in the second; at 10 fps the one frame
    left is the empty first one, which was written and could not be read back."""
    folder = tmp_path / "clip"
    folder.mkdir()
    person = np.c_[np.random.default_rng(0).uniform(100, 400, (25, 2)), np.full(25, 0.8)].ravel().tolist()
    for t, people in enumerate([[], [{"pose_keypoints_2d": person}]]):
        (folder / f"c_{t:012d}_keypoints.json").write_text(json.dumps({"version": 1.3, "people": people}))
    for out in ("out.csv", "out.npz", "outdir"):
        result = invoke("pose", "convert", folder, tmp_path / out, "--fps", "10")
        lines = [line for line in result.output.splitlines() if line.strip()]
        assert result.exit_code == 2 and len(lines) == 1, result.output
        assert "nothing to write" in lines[0] and "--fps 10 keeps 1 frame(s)" in lines[0]
        assert not (tmp_path / out).exists()
    assert invoke("pose", "convert", folder, tmp_path / "ok.csv", "--fps", "30").exit_code == 0


def test_convert_chain(tmp_path, walking_track):
    joints = walking_track.joints.copy()
    joints[10:12, 4] = np.nan
    write_track(walking_track.replace(joints=joints), tmp_path / "in.npz")
    result = invoke("pose", "convert", tmp_path / "in.npz", tmp_path / "out", "--fill-gaps", "3", "--smooth", "1",
                    "--fps", "15", "--to-layout", "body15")
    assert result.exit_code == 0, result.output
    assert "filled 1 gaps" in result.output and "wrote" in result.output
    out = read_track(tmp_path / "out")
    assert out.layout == "body15" and out.fps == 15.0 and out.num_frames == 20 and not out.missing.any()
    again = invoke("pose", "convert", tmp_path / "in.npz", tmp_path / "out")
    assert again.exit_code == 2 and "already exists" in again.output
    assert invoke("pose", "convert", tmp_path / "in.npz", tmp_path / "out", "--overwrite").exit_code == 0
    assert read_track(tmp_path / "out").num_frames == 40


def test_show_over_black_and_over_frames(tmp_path, walking_track):
    track = walking_track.frames(0, 5)
    write_track(track, tmp_path / "p.npz")
    result = invoke("pose", "show", tmp_path / "p.npz", "--out", tmp_path / "a.mp4")
    assert result.exit_code == 0, result.output
    assert len(read_frames(tmp_path / "a.mp4")) == 5
    with VideoWriter(tmp_path / "bg.mp4", fps=30) as video:
        for _ in range(5):
            video.write(np.full((240, 320, 3), 90, np.uint8))
    result = invoke("pose", "show", tmp_path / "p.npz", "--out", tmp_path / "b.mp4", "--frames", tmp_path / "bg.mp4")
    assert result.exit_code == 0, result.output
    source = read_frames(tmp_path / "b.mp4")
    assert source.size == (320, 240) and len(source) == 5
    first = next(iter(source))
    assert abs(int(first[2, 2].mean()) - 90) < 6  # background kept


def test_extract_from_an_image_folder(tmp_path):
    pytest.importorskip("mediapipe")
    skimage_data = pytest.importorskip("skimage.data")
    import cv2

    (tmp_path / "frames").mkdir()
    cv2.imwrite(str(tmp_path / "frames" / "0.png"), cv2.cvtColor(skimage_data.astronaut(), cv2.COLOR_RGB2BGR))
    result = invoke("pose", "extract", tmp_path / "frames", "--out", tmp_path / "out")
    assert result.exit_code == 0, result.output
    assert "person found in 1 of 1 frames" in result.output
    track = read_track(tmp_path / "out" / "poses")
    assert track.layout == "body25" and track.image_size == (512, 512) and not track.missing[0, 0]
