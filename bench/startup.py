"""Stage `startup`: a whole `clone retarget apply` run on a 120-frame track, and how much of it is start-up.

Each figure is the median wall time of a whole subprocess. First row: ``clone retarget apply`` as it runs by
default (numpy: the packaged weights have an ``.npz`` export, torch is never imported; the driver's motion codes
refined by 30 Adam steps, :mod:`retarget.inference.numpy_refine`) against the same command with ``--backend
torch`` (the default before numpy refined codes). Then, as shares of the default run: ``--refine-steps 0`` (the
network alone), ``python -c "import clone.cli.main"`` (the CLI's own import cost), ``clone --help``, ``python -c
"import torch"`` (what the numpy path saves) and the bare interpreter.
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


def clone_exe() -> list[str]:
    """The `clone` console script of this interpreter's environment (or ``python -m clone``)."""
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

    repeats = 2 if quick else 5
    tmp = Path(tempfile.mkdtemp(prefix="bench_startup_"))
    try:
        source, origin = source_track()
        track_path = write_track(tiled(source, 120), tmp / "track.npz")
        out = tmp / "out.npz"
        # One thread everywhere: `clone` picks the free cores itself, which on a shared machine may be 1 or 2.
        default_cmd = [*clone_exe(), "retarget", "apply", str(track_path), "--skeleton", str(track_path),
                       "--out", str(out), "--device", "cpu", "--threads", "1"]
        t0 = time.perf_counter()
        torch_s = _timed([*default_cmd, "--backend", "torch"], repeats, out)
        apply_s = _timed(default_cmd, repeats, out)
        case = "clone retarget apply, 120 frames"
        rows = [row(case, "whole subprocess as by default (numpy, motion codes refined, no torch import)", apply_s,
                    "s", torch_s, "the same with --backend torch", higher_is_better=False, share_of_apply=1.0)]  # fmt: skip
        others = {
            "whole subprocess, --refine-steps 0 (numpy, the network alone)": [*default_cmd, "--refine-steps", "0"],
            'python -c "import clone.cli.main"': [sys.executable, "-c", "import clone.cli.main"],
            "clone --help": [*clone_exe(), "--help"],
            'python -c "import torch"': [sys.executable, "-c", "import torch"],
            "python -c pass (interpreter)": [sys.executable, "-c", "pass"],
        }
        for name, cmd in others.items():
            t = _timed(cmd, repeats, out)
            rows.append(row(case, name, t, "s", apply_s, "clone retarget apply (default)", higher_is_better=False,
                            share_of_apply=round(t / apply_s, 3)))  # fmt: skip
        return {
            "rows": rows,
            "notes": [
                f"input: {origin}, 120 frames as npz; the track is also the --skeleton; --threads 1",
                ("first row: speedup = torch-path time / numpy-path time; other rows: share_of_apply = this time "
                 "/ the default run's"),
                f"{repeats} runs each after 1 warm-up; stage took {time.perf_counter() - t0:.0f} s",
            ],
        }
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
