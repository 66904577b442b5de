import shutil

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
