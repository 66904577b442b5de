"""Running the walkthroughs of examples/ in tests: the venv's `clone` on PATH, tiny inputs built in tmp_path."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def run_example(args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    """Run one example command with the venv's `clone` first on PATH; fail the test on a non-zero exit."""
    env = dict(os.environ)
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    result = subprocess.run(args, cwd=cwd, env=env, capture_output=True, text=True, timeout=600, check=False)
    assert result.returncode == 0, result.stdout[-2000:] + result.stderr[-2000:]
    return result


def write_people(folder: Path, frames: int) -> Path:
    """Two OpenPose folders like the authors' examples, ``folder/tall_man`` and ``folder/small_man``."""
    from pose_io.writers import write_track
    from tests.figures import tall_and_small

    for name, track in tall_and_small(frames).items():
        write_track(track, folder / f"{name}_man")
    return folder
