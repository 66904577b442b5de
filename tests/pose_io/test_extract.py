import sys

import numpy as np
import pytest

from pose_io import InputError, read_track
from pose_io.extract import INSTALL_HINT, extract_video, load_mediapipe_pose
from pose_io.video import read_frames
from pose_io.video_out import VideoWriter
from tests.pose_io.media import write_grey_video


def mediapipe_available() -> bool:
    try:
        load_mediapipe_pose()
    except InputError:
        return False
    return True


@pytest.fixture
def astronaut_video(tmp_path):
    skimage_data = pytest.importorskip("skimage.data")
    path = tmp_path / "astronaut.mp4"
    with VideoWriter(path, fps=24) as video:
        video.write(skimage_data.astronaut())  # [512, 512, 3] uint8 RGB
    return path


@pytest.mark.skipif(not mediapipe_available(), reason="mediapipe is not installed")
def test_extract_finds_the_astronaut(astronaut_video, tmp_path):
    out = tmp_path / "out"
    calls = []
    result = extract_video(astronaut_video, out, progress=lambda done, total: calls.append((done, total)))
    assert calls == [(1, 1)] and result.frames_with_person == 1
    assert sorted(p.name for p in (out / "frames").iterdir()) == ["000000.png"]
    track = read_track(out / "poses")
    assert track.layout == "body25" and track.image_size == (512, 512) and track.fps == 24.0
    assert track.equals(result.track)
    nose, l_sh, r_sh = (track.joint(n)[0] for n in ("nose", "l_shoulder", "r_shoulder"))
    # The astronaut faces the camera: her face is at about (220, 130), shoulders below it on either side.
    assert 160 < nose[0] < 280 and 60 < nose[1] < 200
    assert r_sh[0] < nose[0] < l_sh[0]
    assert l_sh[1] > nose[1] + 40 and r_sh[1] > nose[1] + 40
    assert np.linalg.norm(l_sh - r_sh) > 100
    neck = track.joint("neck")[0]
    np.testing.assert_allclose(neck, (l_sh + r_sh) / 2, atol=1e-3)
    assert track.missing[0, track.joint_layout.index("l_small_toe")]
    frame = next(iter(read_frames(out / "frames")))
    assert frame.shape == (512, 512, 3)


@pytest.mark.skipif(not mediapipe_available(), reason="mediapipe is not installed")
def test_no_person_writes_nothing(tmp_path):
    path = write_grey_video(tmp_path / "grey.mp4")
    with pytest.raises(InputError, match="no person in any of 2 frames"):
        extract_video(path, tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_missing_mediapipe_gives_the_install_line(monkeypatch, tmp_path):
    for name in ("mediapipe", "mediapipe.python", "mediapipe.python.solutions", "mediapipe.python.solutions.pose"):
        monkeypatch.setitem(sys.modules, name, None)
    with pytest.raises(InputError, match="pip install mediapipe==0.10.14 --no-deps") as info:
        extract_video(tmp_path / "whatever.mp4", tmp_path / "out")
    assert str(info.value) == INSTALL_HINT and "\n" not in INSTALL_HINT
    assert not (tmp_path / "out").exists()
