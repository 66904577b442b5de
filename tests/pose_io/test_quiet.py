import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from pose_io.quiet import is_third_party, quiet_native_logs
from pose_io.video_out import VideoWriter

NATIVE = (
    ("W0000 00:00:1796581691.408709   13407 inference_feedback_manager.cc:114] Feedback manager requires a model "
     "with a single signature inference. Disabling support for feedback tensors."),
    "INFO: Created TensorFlow Lite XNNPACK delegate for CPU.",
    "WARNING: All log messages before absl::InitializeLog() is called are written to STDERR",
    "I0000 00:00:1796581691.1   13407 gl_context.cc:357] GL version: 2.1",
)


@pytest.mark.parametrize("line", NATIVE)
def test_native_log_lines_are_recognised(line):
    assert is_third_party(line)


@pytest.mark.parametrize("line", ["error: cannot read video.mp4", "Traceback (most recent call last):",
                                  "WARNING: the driver has no audio", "INFO: 3 frames"])
def test_messages_for_the_user_are_not(line):
    assert not is_third_party(line)


def test_descriptor_2_is_filtered_and_python_stderr_still_reaches_the_terminal(capfd):
    with quiet_native_logs():
        os.write(2, ("\n".join(NATIVE) + "\n").encode())
        os.write(2, b"a real native error\n")
        print("bar drawn", file=sys.stderr)
    err = capfd.readouterr().err
    assert "bar drawn" in err and "a real native error" in err
    assert not any(line in err for line in NATIVE)
    os.write(2, b"after\n")  # descriptor 2 is the terminal again
    assert capfd.readouterr().err == "after\n"


def test_an_error_inside_still_restores_descriptor_2(capfd):
    with pytest.raises(RuntimeError), quiet_native_logs():
        raise RuntimeError("boom")
    os.write(2, b"restored\n")
    assert capfd.readouterr().err == "restored\n"


def test_extraction_prints_no_third_party_line(tmp_path):
    pytest.importorskip("mediapipe")
    skimage_data = pytest.importorskip("skimage.data")
    video = tmp_path / "astronaut.mp4"
    with VideoWriter(video, fps=24) as out:
        for _ in range(3):
            out.write(skimage_data.astronaut())
    clone = Path(sys.executable).with_name("clone")
    run = subprocess.run([str(clone), "pose", "extract", str(video), "--out", str(tmp_path / "out")],
                         check=False, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    lines = [ln for ln in (run.stdout + run.stderr).replace("\r", "\n").splitlines() if ln.strip()]
    assert not [ln for ln in lines if is_third_party(ln) or "TensorFlow" in ln or ".cc:" in ln], lines
    assert np.any([ln.startswith("wrote ") for ln in lines])
