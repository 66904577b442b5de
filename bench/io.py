"""Stage `io`: pose-track write and read rates (frames/s) of CSV, npz and OpenPose JSON at 10k and 100k frames.

Every format is compared with the plainest code that moves the same numbers, measured in the same run:

- CSV: ``np.savetxt`` / ``np.loadtxt`` of the [T, J * 3] array (numpy's text writer and C parser; no
  header checks, no missing joints, no validation, not atomic);
- npz: ``np.savez_compressed`` / ``np.load`` of the joints and confidence arrays alone;
- OpenPose: one ``json.dumps`` / ``json.loads`` file per frame (no sidecar, no checks, not atomic).

So the ratio is what our formatting, validation (limits, outliers), person following and atomic writes
cost, and a writer or reader that is not linear in the track length shows as a ratio that falls from 10k
to 100k frames. Each sample writes to a fresh path; deleting it is not timed. The 100k-frame OpenPose
folder is 100,000 files (~150 MB); it is written twice and removed at once.
"""

from __future__ import annotations

import json
import shutil
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from bench.harness import Timing, row

LAYOUT = "body25"


def _track(frames: int) -> Any:
    """``frames`` frames of a jittered figure in a 640x480 frame, one joint missing every 7th frame."""
    from pose_io.layouts import get_layout
    from pose_io.track import PoseTrack

    n = len(get_layout(LAYOUT))
    rng = np.random.default_rng(0)
    joints = (rng.uniform(150, 450, (1, n, 2)) + rng.normal(0, 3, (frames, n, 2))).astype(np.float32)
    conf = rng.uniform(0.3, 1.0, (frames, n)).astype(np.float32)
    conf[::7, 3] = 0.0
    return PoseTrack(joints, conf, 30.0, (640, 480), LAYOUT)


def _timed(make: Callable[[Path], object], folder: Path, name: str, repeats: int, warmup: bool) -> tuple[Timing, Path]:
    """Median seconds of ``make(path)``, and the path it last wrote (kept for reading).

    Each run starts from a missing path; removing the previous output is not timed.
    """
    samples, path = [], folder / name
    for r in range(repeats + warmup):
        if path.exists():
            shutil.rmtree(path) if path.is_dir() else path.unlink()
        start = time.perf_counter()
        make(path)
        if r >= warmup:
            samples.append(time.perf_counter() - start)
    return Timing(statistics.median(samples), repeats, samples), path


def _timed_read(read: Callable[[], object], repeats: int, warmup: bool) -> Timing:
    samples = []
    for r in range(repeats + warmup):
        start = time.perf_counter()
        read()
        if r >= warmup:
            samples.append(time.perf_counter() - start)
    return Timing(statistics.median(samples), repeats, samples)


def _plain_npz_read(path: Path) -> list[np.ndarray]:
    with np.load(path) as archive:
        return [archive[k] for k in ("joints", "confidence")]


def _plain_openpose(xyc: np.ndarray, folder: Path) -> None:
    folder.mkdir()
    for t, values in enumerate(xyc.reshape(len(xyc), -1).tolist()):
        (folder / f"p_{t:012d}_keypoints.json").write_text(json.dumps({"people": [{"pose_keypoints_2d": values}]}))


def _plain_openpose_read(folder: Path) -> list:
    return [json.loads(p.read_bytes()) for p in sorted(folder.iterdir())]


def _rows(frames: int, reps: int, folder: Path) -> list[dict[str, object]]:
    """Write and read rows of the three formats for one track length."""
    from pose_io.readers import read_track
    from pose_io.writers import write_track

    track = _track(frames)
    xyc = np.concatenate([np.nan_to_num(track.joints), track.confidence[..., None]], axis=-1)  # [T, J, 3]
    flat = xyc.reshape(frames, -1)  # [T, J * 3]
    plain: dict[str, tuple[str, Callable[[Path], object], Callable[[Path], object]]] = {
        ".csv": ("np.savetxt / np.loadtxt of [T, J*3]", lambda p: np.savetxt(p, flat, fmt="%.9g", delimiter=","),
                 lambda p: np.loadtxt(p, delimiter=",")),
        ".npz": ("np.savez_compressed / np.load of the two arrays",
                 lambda p: np.savez_compressed(p, joints=track.joints, confidence=track.confidence), _plain_npz_read),
        "": ("json.dumps / json.loads, one file per frame", lambda p: _plain_openpose(xyc, p), _plain_openpose_read),
    }
    rows = []
    warmup = frames <= 50_000  # a long track is its own warm-up; its files take minutes to write
    for suffix, (label, plain_write, plain_read) in plain.items():
        fmt = suffix[1:] or "openpose"
        base_w, plain_path = _timed(plain_write, folder, f"plain-{fmt}{suffix}", reps, warmup)
        ours_w, ours_path = _timed(lambda p: write_track(track, p), folder, f"ours-{fmt}{suffix}", reps, warmup)
        base_r = _timed_read(lambda r=plain_read, p=plain_path: r(p), reps, warmup)
        ours_r = _timed_read(lambda p=ours_path: read_track(p), reps, warmup)
        for path in (plain_path, ours_path):
            shutil.rmtree(path) if path.is_dir() else path.unlink()
        case = f"{frames:,} frames, {LAYOUT}"
        rows += [
            row(case, f"{fmt} write (write_track)", ours_w.rate(frames), "frames/s", base_w.rate(frames), label,
                seconds=ours_w.median_s, repeats=reps),
            row(case, f"{fmt} read (read_track)", ours_r.rate(frames), "frames/s", base_r.rate(frames), label,
                seconds=ours_r.median_s, repeats=reps),
        ]
    return rows


def run(quick: bool = False, repeats: int | None = None, **_: object) -> dict[str, Any]:
    sizes = (2_000, 20_000) if quick else (10_000, 100_000)
    rows = []
    with tempfile.TemporaryDirectory(prefix="clone2d-bench-io-") as tmp:
        for frames in sizes:
            rows += _rows(frames, repeats or (1 if frames > 50_000 or quick else 3), Path(tmp))
    notes = [
        (f"sizes {', '.join(f'{s:,}' for s in sizes)} frames of {LAYOUT}; each sample writes a fresh path "
         "(deleting it is not timed); below 50,000 frames the first run of each is a warm-up"),
        "read_track includes validation, outlier dropping and person following; write_track is atomic",
        "a linear writer or reader keeps its speedup from the smaller to the larger size",
    ]
    return {"rows": rows, "notes": notes}
