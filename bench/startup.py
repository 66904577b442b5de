"""Stage `startup`: how much of a `clone retarget apply` run on a 120-frame track is start-up.

Each figure is the median wall time of a whole subprocess: ``clone retarget apply`` (reads the track,
loads the network, retargets, writes npz), against ``python -c "import clone.cli.main"`` (the CLI's own
import cost), ``clone --help`` and ``python -c "import torch"``; the share is their time over apply's.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from bench.data import source_track, tiled
from bench.harness import row, time_call


def _clone_exe() -> list[str]:
    exe = Path(sys.executable).with_name("clone")
    return [str(exe)] if exe.is_file() else [sys.executable, "-m", "clone"]


def _timed(cmd: list[str], repeats: int, cleanup: Path | None = None) -> float:
    def call() -> None:
        if cleanup is not None and cleanup.exists():
            cleanup.unlink()
        subprocess.run(cmd, check=True, capture_output=True)

    return time_call(call, repeats, 1).median_s


def run(quick: bool = False, **_: object) -> dict[str, Any]:
    from pose_io.writers import write_track

    repeats = 2 if quick else 3
    tmp = Path(tempfile.mkdtemp(prefix="bench_startup_"))
    try:
        source, origin = source_track()
        track_path = write_track(tiled(source, 120), tmp / "track.npz")
        out = tmp / "out.npz"
        # One thread everywhere: `clone` picks the free cores itself, which on a shared machine may be 1 or 2.
        apply_cmd = [*_clone_exe(), "retarget", "apply", str(track_path), "--skeleton", str(track_path),
                     "--out", str(out), "--device", "cpu"]
        t0 = time.perf_counter()
        apply_s = _timed(apply_cmd, repeats, out)
        others = {
            'python -c "import clone.cli.main"': [sys.executable, "-c", "import clone.cli.main"],
            "clone --help": [*_clone_exe(), "--help"],
            'python -c "import torch"': [sys.executable, "-c", "import torch"],
            "python -c pass (interpreter)": [sys.executable, "-c", "pass"],
        }
        rows = [row("clone retarget apply, 120 frames", "whole subprocess", apply_s, "s", apply_s,
                    "clone retarget apply", higher_is_better=False, share_of_apply=1.0)]
        for name, cmd in others.items():
            t = _timed(cmd, repeats)
            rows.append(row("clone retarget apply, 120 frames", name, t, "s", apply_s, "clone retarget apply",
                            higher_is_better=False, share_of_apply=round(t / apply_s, 3)))
        return {
            "rows": rows,
            "notes": [
                f"input: {origin}, 120 frames as npz; the track is also the --skeleton",
                "speedup column here = apply time / this time; share_of_apply = this time / apply time",
                f"{repeats} runs each after 1 warm-up; stage took {time.perf_counter() - t0:.0f} s",
            ],
        }
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
