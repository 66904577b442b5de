"""Stage `extract`: pose extraction from real video (MediaPipe, as `clone train-ref VIDEO` and `clone drive VIDEO`
run it), its rate and its memory, against decoding the same frames alone in the same run.

Each case runs `clone pose info VIDEO` as its own process, with an empty pose cache (``CLONE2D_CACHE`` in a
temporary folder), and samples the process's resident memory (``/proc/PID/status``) every 0.2 s:

- 720p: ``../shared/real/street_openpose.avi`` (1280x720, a crowded street) as it is;
- 4K: the same clip scaled to 3840x2160 with the bundled ffmpeg: the frames are 9x larger, the memory must not be;
- long: the 720p clip looped to ``LOOPS`` times its length: memory flat over the run (the growth from the first
  quarter's peak to the last quarter's, against the peak), as a one-hour video needs.

Rates are frames over the whole command (start-up included, so a short clip reads lower than a long one);
the baseline is decoding the same video alone (``pose_io.video.read_frames``). The videos are test material,
read from ../shared/real and written only to a temporary folder.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

SHARED_REAL = Path(__file__).resolve().parents[2] / "shared" / "real"
CLIP = "street_openpose.avi"
LOOPS = 6


def _ffmpeg(*args: str) -> None:
    import imageio_ffmpeg

    subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-hide_banner", "-loglevel", "error", "-nostdin", "-y", *args],
                   check=True)


def _rss_mb(pid: int) -> float | None:
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    except OSError:
        return None
    return None


def _extract(video: Path, cache: Path) -> dict[str, float]:
    """`clone pose info VIDEO` in its own process: seconds, peak RSS and the RSS samples' growth."""
    clone = Path(sys.executable).with_name("clone")
    env = {**os.environ, "CLONE2D_CACHE": str(cache)}
    shutil.rmtree(cache, ignore_errors=True)
    t0 = time.perf_counter()
    proc = subprocess.Popen([str(clone), "pose", "info", str(video)], env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True)
    samples: list[tuple[float, float]] = []
    while proc.poll() is None:
        rss = _rss_mb(proc.pid)
        if rss is not None:
            samples.append((time.perf_counter() - t0, rss))
        time.sleep(0.2)
    seconds = time.perf_counter() - t0
    err = proc.stderr.read() if proc.stderr else ""
    if proc.returncode != 0:
        raise RuntimeError(f"clone pose info {video} failed: {err.strip()[-300:]}")
    values = [r for _, r in samples]
    quarter = max(1, len(samples) // 4)
    return {"seconds": seconds, "peak_rss_mb": max(values) if values else float("nan"),
            "first_quarter_peak_mb": max(values[:quarter]) if values else float("nan"),
            "last_quarter_peak_mb": max(values[-quarter:]) if values else float("nan")}


def _decode_seconds(video: Path) -> tuple[float, int]:
    from pose_io.video import read_frames

    t0 = time.perf_counter()
    count = sum(1 for _ in read_frames(video))
    return time.perf_counter() - t0, count


def run(quick: bool = False, **_: object) -> dict[str, Any]:
    from bench.harness import row

    clip = SHARED_REAL / CLIP
    if not clip.is_file():
        return {"skipped": f"no {CLIP} in {SHARED_REAL}"}
    tmp = Path(tempfile.mkdtemp(prefix="bench_extract_"))
    rows = []
    try:
        cases = [("720p", clip)]
        if not quick:
            big = tmp / "street_4k.mp4"
            _ffmpeg("-i", str(clip), "-vf", "scale=3840:2160", "-c:v", "libx264", "-preset", "ultrafast",
                    "-crf", "20", "-an", str(big))
            cases.append(("4K (3840x2160)", big))
            long = tmp / "street_long.mp4"
            _ffmpeg("-stream_loop", str(LOOPS - 1), "-i", str(clip), "-c:v", "libx264", "-preset", "ultrafast",
                    "-crf", "20", "-an", str(long))
            cases.append((f"720p looped {LOOPS}x", long))
        for name, video in cases:
            measured = _extract(video, tmp / "cache")
            decode_s, frames = _decode_seconds(video)
            growth = measured["last_quarter_peak_mb"] - measured["first_quarter_peak_mb"]
            rows.append(row(
                f"pose extraction, {CLIP} {name}, {frames} frames, `clone pose info` as a process",
                "MediaPipe Pose, whole command", frames / measured["seconds"], "frames/s",
                baseline=frames / decode_s, baseline_variant="decoding the frames alone (no poses)",
                frames=frames, seconds=round(measured["seconds"], 2), peak_rss_mb=round(measured["peak_rss_mb"], 1),
                rss_growth_mb=round(growth, 1),
            ))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return {"rows": rows}
