import numpy as np
import pytest

from pose_io.audio import has_audio, resolve_audio
from pose_io.errors import InputError
from pose_io.video_out import VideoWriter
from tests.pose_io.media import media_info, write_tone


def silent_video(path, frames=12, fps=12.0, audio=None):
    with VideoWriter(path, fps=fps, audio=audio) as video:
        for t in range(frames):
            video.write(np.full((32, 48, 3), 10 * t, np.uint8))
    return path


def test_sound_is_cut_to_the_video(tmp_path):
    tone = write_tone(tmp_path / "tone.wav", 3.0)
    assert has_audio(tone)
    out = silent_video(tmp_path / "out.mp4", frames=12, fps=12.0, audio=tone)  # 1 s of video, 3 s of sound
    sound, duration = media_info(out)
    assert sound and abs(duration - 1.0) < 0.1
    assert not list(tmp_path.glob(".*"))  # no temporary file outlives the write


def test_a_shorter_sound_keeps_the_whole_video(tmp_path):
    tone = write_tone(tmp_path / "tone.wav", 0.5)
    sound, duration = media_info(silent_video(tmp_path / "out.mp4", frames=24, fps=12.0, audio=tone))
    assert sound and abs(duration - 2.0) < 0.1


def test_resolve_audio(tmp_path):
    video = silent_video(tmp_path / "silent.mp4")
    assert not has_audio(video) and not has_audio(tmp_path / "missing.wav")
    assert resolve_audio("auto", video) is None  # a driver without sound gives a silent output
    assert resolve_audio("none", video) is None and resolve_audio(None, video) is None
    tone = write_tone(tmp_path / "tone.wav", 1.0)
    with_sound = silent_video(tmp_path / "sound.mp4", audio=tone)
    assert resolve_audio("auto", with_sound) == with_sound
    assert resolve_audio(tone, video) == tone
    assert resolve_audio("auto", tmp_path / "poses_folder") is None
    with pytest.raises(InputError, match="no such file"):
        resolve_audio(tmp_path / "nope.mp3", video)
    with pytest.raises(InputError, match="no audio stream"):
        resolve_audio(video, video)
    text = tmp_path / "notes.txt"
    text.write_text("not a sound")
    with pytest.raises(InputError, match="no audio stream"):
        resolve_audio(text, video)
