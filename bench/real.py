"""Stage `real` (opt-in): held-out reconstruction of real people, one row per reference video in ../shared/real.

For each fashion reference (``ubc_*.mp4``): MediaPipe poses of the whole video (cached by content); the first 80 %
of the frames train a 256² model as ``clone train-ref`` does, for each budget of ``--minutes`` (default 3,
``--quick`` 1, e.g. ``--minutes 1,3,10``; two threads) and from each start: the shipped generator prior (the
command's default) and random weights (``--init none``). The last 20 %, never trained on, are driven back from
their own poses (``--method none``, as `clone drive` does it) and compared with the real frames cut to the model's
canvas:

- SSIM / PSNR of the whole canvas, of the person's box (the pose's box and 15 % around it) and SSIM of the face's
  box (around the nose, eyes, ears and mouth, a sixth of the body's height across);
- flicker: the mean absolute change between consecutive frames inside the person's box, generated against the
  real video's own (1.0: as steady as the real footage);
- pose consistency when the real dancer (``dance_musepose.mp4``) drives the model (`clone drive`'s defaults),
  retargeted and by global scaling: MediaPipe on the generated frames against the driven poses, PCK@0.1 and median error.

Baseline: the same measures for the model's background plate alone (no person), against the same frames.
``run(strips=DIR)`` also writes real | generated strips of held-out frames into DIR, to look at (they show the
research-only footage: keep them out of the repository).
The videos are test material: they are read from ../shared/real, never copied.
"""

from __future__ import annotations

import json
import logging
import shutil
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

log = logging.getLogger("bench.real")
SHARED_REAL = Path(__file__).resolve().parents[2] / "shared" / "real"
SIZE = 256
HELD_OUT = 0.2


def _box_scores(pred: np.ndarray, truth: np.ndarray, box: tuple[int, int, int, int] | None) -> tuple[float, float]:
    from clone.metrics import frame_pair_scores

    if box is None:
        return float("nan"), float("nan")
    x0, y0, x1, y1 = box
    return frame_pair_scores(pred[y0:y1, x0:x1], truth[y0:y1, x0:x1])


def face_box(joints: np.ndarray, layout, height: float, size: int) -> tuple[int, int, int, int] | None:
    """A square around the face points (nose, eyes, ears, mouth corners) a sixth of ``height`` across."""
    from clone.model.face import FACE_POINTS

    names = [n for n in FACE_POINTS if layout.has(n)]
    points = joints[[layout.index(n) for n in names]]
    points = points[np.isfinite(points).all(axis=-1)]
    if not len(points):
        return None
    cx, cy = points.mean(axis=0)
    half = max(4.0, height / 12.0)
    x0, y0 = int(max(0, np.floor(cx - half))), int(max(0, np.floor(cy - half)))
    x1, y1 = int(min(size, np.ceil(cx + half))), int(min(size, np.ceil(cy + half)))
    return (x0, y0, x1, y1) if x1 - x0 >= 7 and y1 - y0 >= 7 else None


def measure(model_path: Path, track, video: Path, start: int, strip: Path | None = None) -> dict[str, float]:
    """Drive the model with frames ``start..`` of ``track`` and score them against the real frames; ``strip``:
    also write real (top) | generated (bottom) of six held-out frames there, to look at."""
    from clone.drive.poses import drive_poses, driver_track
    from clone.metrics import FlickerMeter, frame_pair_scores, person_box
    from clone.model.canvas import cut_frame, image_to_canvas
    from clone.model.reference import load_reference_model
    from clone.runtime.generate import generate_frames
    from pose_io.measures import skeleton_height
    from pose_io.video import read_frames

    model = load_reference_model(model_path)
    held = track.frames(start, track.num_frames)
    driver = driver_track(held, 5, "held-out", model.pose_layout)
    driven, _ = drive_poses(driver, model, "none", None, "cpu", "raw", False, 0)
    canvas_joints = image_to_canvas(driven.joints, model.canvas)  # [T, J, 2]
    layout = driven.joint_layout
    body = canvas_joints[:, : 15]
    height = skeleton_height(body, "body15")
    truths = [cut_frame(f, model.canvas) for t, f in enumerate(read_frames(video)) if start <= t < track.num_frames]
    preds = [frame for _map, frame in generate_frames(model, driven, "cpu")]
    plate = model.plate
    rows: dict[str, list[float]] = {k: [] for k in ("ssim", "psnr", "person_ssim", "person_psnr", "face_ssim",
                                                    "plate_person_ssim", "plate_face_ssim")}
    for t, (pred, truth) in enumerate(zip(preds, truths)):
        s, p = frame_pair_scores(pred, truth)
        box = person_box(body[t], (SIZE, SIZE))
        face = face_box(canvas_joints[t], layout, height, SIZE)
        ps, pp = _box_scores(pred, truth, box)
        fs, _ = _box_scores(pred, truth, face)
        rows["ssim"].append(s), rows["psnr"].append(p), rows["person_ssim"].append(ps)
        rows["person_psnr"].append(pp), rows["face_ssim"].append(fs)
        if plate is not None:
            rows["plate_person_ssim"].append(_box_scores(plate, truth, box)[0])
            rows["plate_face_ssim"].append(_box_scores(plate, truth, face)[0])
    out = {k: float(np.nanmean(v)) if v else float("nan") for k, v in rows.items()}

    def flicker(frames: list[np.ndarray]) -> float:
        meter = FlickerMeter()
        for t, frame in enumerate(frames):
            meter.add(frame, body[t])
        return meter.value()

    out["flicker_ratio"] = flicker(preds) / flicker(truths)
    if strip is not None:
        import cv2

        picks = np.linspace(0, len(preds) - 1, 6).round().astype(int)
        image = np.concatenate([np.concatenate([truths[i] for i in picks], axis=1),
                                np.concatenate([preds[i] for i in picks], axis=1)], axis=0)
        cv2.imwrite(str(strip), cv2.cvtColor(image, cv2.COLOR_RGB2BGR))
    out["held_out_frames"] = len(preds)
    return out


def drive_consistency(model_path: Path, driver_video: Path, method: str) -> dict[str, float]:
    """The real dancer drives the model (`clone drive`'s poses, ``method``); MediaPipe on the generated frames
    against the driven poses (:func:`clone.metrics.consistency.pose_consistency`)."""
    from clone.drive.poses import drive_poses, read_driver
    from clone.metrics.consistency import pose_consistency
    from clone.model.canvas import image_to_canvas
    from clone.model.reference import load_reference_model
    from clone.runtime.generate import generate_frames

    model = load_reference_model(model_path)
    driver = read_driver(driver_video, 5, layout=model.pose_layout)
    driven, _ = drive_poses(driver, model, method)
    frames = [frame for _map, frame in generate_frames(model, driven, "cpu")]
    body = image_to_canvas(driven.to_layout("body15").joints, model.canvas)
    return pose_consistency(frames, body, driven.fps)


STARTS = {"prior": "from the shipped prior", "none": "from random weights (--init none)"}


def budgets(quick: bool, minutes: float | str | None) -> list[float]:
    """Training budgets in minutes: ``minutes`` (a number or a comma-separated list), else 1 (quick) or 3."""
    if minutes is None:
        return [1.0 if quick else 3.0]
    values = [float(m) for m in str(minutes).split(",") if m.strip()]
    if not values or not all(0 < m < 600 for m in values):
        raise ValueError(f"minutes {minutes!r}: give one or more budgets, each above 0 and below 600")
    return values


def chosen_starts(starts: str | None) -> list[str]:
    """The starts to train from: ``starts`` (comma-separated names of :data:`STARTS`), else all of them."""
    if starts is None:
        return list(STARTS)
    names = [s.strip() for s in starts.split(",") if s.strip()]
    unknown = sorted(set(names) - set(STARTS))
    if not names or unknown:
        raise ValueError(f"starts {starts!r}: choose from {', '.join(STARTS)}")
    return list(dict.fromkeys(names))


def run(quick: bool = False, minutes: float | str | None = None, strips: Path | None = None,
        starts: str | None = None, **_: object) -> dict[str, Any]:
    import torch

    from bench.harness import row
    from clone.train_ref import TrainConfig, train_reference
    from clone.train_ref.prior import matching_prior
    from pose_io.readers import read_track
    from pose_io.writers import write_track

    videos = sorted(SHARED_REAL.glob("ubc_*.mp4"))
    if not videos:
        return {"skipped": f"no reference videos in {SHARED_REAL}"}
    config = TrainConfig(size=SIZE, seed=0)
    prior = matching_prior(config)
    starts = [s for s in chosen_starts(starts) if s != "prior" or prior is not None]
    torch.set_num_threads(2)
    if strips is not None:
        Path(strips).mkdir(parents=True, exist_ok=True)
    rows = []
    tmp = Path(tempfile.mkdtemp(prefix="bench_real_"))
    try:
        for video in videos:
            track = read_track(video)
            start = round(track.num_frames * (1 - HELD_OUT))
            poses = write_track(track.frames(0, start), tmp / f"{video.stem}.npz")
            for budget in budgets(quick, minutes):
                for begin in starts:
                    model = tmp / f"{video.stem}_{budget:g}_{begin}.pt"
                    t0 = time.perf_counter()
                    result = train_reference(poses, video, model, config=config, minutes=budget, device="cpu",
                                             align="trim", init=prior if begin == "prior" else None)
                    seconds = time.perf_counter() - t0
                    strip = None if strips is None else Path(strips) / f"real_{video.stem}_{budget:g}_{begin}.png"
                    scores = measure(model, track, video, start, strip)
                    dancer = SHARED_REAL / "dance_musepose.mp4"
                    if dancer.is_file():
                        for method in ("retarget", "global-scale"):
                            for key, value in drive_consistency(model, dancer, method).items():
                                scores[f"dancer_{method}_{key}"] = value
                    rows.append(row(
                        f"real reference {video.name}: last {HELD_OUT:.0%} of frames held out, {SIZE}² canvas",
                        f"{budget:g} min of train-ref {STARTS[begin]}", scores["person_ssim"], "person box SSIM",
                        baseline=scores["plate_person_ssim"], baseline_variant="the background plate alone",
                        **scores, steps=result.steps, train_seconds=round(seconds, 1), frames_trained=start,
                    ))
                    log.info("%s", json.dumps({"video": video.name, "minutes": budget, "start": begin,
                                               "steps": result.steps, **scores}))  # a long run's rows, as they come
                    model.unlink(missing_ok=True)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return {"rows": rows}
