import shutil
from pathlib import Path

import numpy as np
import pytest

from pose_io import extract
from pose_io.errors import InputError
from pose_io.readers import detect_format, read_track
from pose_io.video_poses import is_video, pose_cache_dir, video_track_path
from tests.pose_io.media import write_grey_video, write_person_video

pytest.importorskip("mediapipe")


@pytest.fixture(autouse=True)
def _cache_in_tmp(tmp_path, monkeypatch):
    monkeypatch.setenv("CLONE2D_CACHE", str(tmp_path / "cache"))


def test_a_video_reads_as_a_track_once_extracted_then_cached(tmp_path, monkeypatch):
    video = write_person_video(tmp_path / "person.mp4", frames=3)
    assert is_video(video) and detect_format(video) == "video"
    track = read_track(video)
    assert track.layout == "mediapipe33" and track.num_frames == 3 and track.fps == 12.0
    assert track.image_size == (256, 256) and (~track.missing).any(axis=1).all()
    assert len(list(pose_cache_dir().glob("*.npz"))) == 1

    def no_extraction(*args, **kwargs):
        raise AssertionError("extracted again")

    monkeypatch.setattr(extract, "extract_track", no_extraction)
    again = read_track(video)
    copy = shutil.copy(video, tmp_path / "renamed copy.mp4")  # the key is the content, not the name
    assert again.equals(track) and read_track(copy).equals(track)
    assert track.to_layout("body31").joint("l_eye").shape == (3, 2)


def test_a_damaged_cache_entry_is_extracted_again(tmp_path):
    video = write_person_video(tmp_path / "person.mp4", frames=2)
    first = read_track(video)
    entry = video_track_path(video)
    entry.write_bytes(b"\x00 not an npz")
    assert read_track(video).equals(first)


def test_a_video_with_nobody_is_one_error_and_caches_nothing(tmp_path):
    video = write_grey_video(tmp_path / "grey.mp4")
    with pytest.raises(InputError, match="no person in any of 2 frames"):
        read_track(video)
    assert not list(pose_cache_dir().glob("*"))


def test_an_unreadable_video_is_one_error(tmp_path):
    bad = tmp_path / "truncated.mp4"
    bad.write_bytes(b"\x00\x00\x00\x18ftypmp42" + b"\x00" * 100)
    with pytest.raises(InputError, match="truncated.mp4"):
        read_track(bad)


def test_ctrl_c_during_extraction_leaves_no_cache_entry_and_no_temp_file(tmp_path):
    """A long video interrupted half-way (SIGINT, as Ctrl-C sends it to the foreground process): the command
    ends without a traceback, and neither the pose cache nor its folder holds anything half-written."""
    import os
    import signal
    import subprocess
    import sys
    import time

    pytest.importorskip("mediapipe")
    skimage_data = pytest.importorskip("skimage.data")
    from pose_io.video_out import VideoWriter

    video = tmp_path / "long.mp4"
    frame = skimage_data.astronaut()[::2, ::2]  # 256x256, a person
    with VideoWriter(video, fps=25) as out:
        for i in range(900):
            out.write(np.roll(frame, i % 9, axis=1))
    cache = tmp_path / "cache"
    env = {**os.environ, "CLONE2D_CACHE": str(cache)}
    clone = Path(sys.executable).with_name("clone")
    # The child must not inherit an ignored SIGINT: a job started in the background by a non-interactive shell
    # (`cmd &`) ignores it, and Python then leaves it ignored. A handled signal is reset to its default on exec.
    inherited = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        proc = subprocess.Popen([str(clone), "pose", "info", str(video)], env=env, stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True)
    finally:
        signal.signal(signal.SIGINT, inherited)
    # Interrupt once extraction has begun (the start-up, imports and MediaPipe's graph, takes 2-3 s; the
    # frames at least as long again).
    time.sleep(4.0)
    assert proc.poll() is None, "extraction ended before it could be interrupted; make the video longer"
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode != 0
    assert "Traceback" not in out + err, err
    left = [p for p in cache.rglob("*") if p.is_file()]
    assert left == [], left
