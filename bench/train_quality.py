"""Stage `train_quality` (opt-in): SSIM on held-out synthetic frames after 1, 3 and 10 minutes of CPU training.

As in ``clone demo`` (quick sizes): the reference video is the tall character dancing the demo's reference
motion (300 frames, 192², yaw 15°); the held-out ground truth is the same character and camera performing
the *driver's* motion (120 frames it never trains on). ``clone.train_ref.train_reference`` trains on the
reference at a 64² canvas (``TrainConfig(size=64)``), a fresh run for each budget (the learning rate falls over
the second half of a run's minutes, so a run resumed from budget to budget would not be a run of that length); after each budget the
generator is driven with the true poses of the held-out clip (``clone.runtime.generate.generate_frames``, each frame
on its own previous output) and scored with SSIM against the true frames cut to the same canvas.
Baseline: SSIM of the median reference frame (background, no performer) against the same true frames.
"""

from __future__ import annotations

import shutil
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

RENDER, CANVAS, REF_FRAMES, GT_FRAMES = 192, 64, 300, 120


def _mean_ssim(preds: list[np.ndarray], truths: list[np.ndarray]) -> float:
    from clone.metrics import frame_pair_scores

    return float(np.mean([frame_pair_scores(p, t)[0] for p, t in zip(preds, truths)]))


def run(quick: bool = False, **_: object) -> dict[str, Any]:
    import cv2
    import torch

    from bench.harness import row
    from clone.demo import demo_motions
    from clone.model.canvas import cut_frame
    from clone.model.reference import load_reference_model
    from clone.runtime.generate import generate_frames
    from clone.synth import get_character, render_performance, save_performance
    from clone.train_ref import TrainConfig, train_reference

    torch.set_num_threads(1)
    budgets = (0.5, 1.0) if quick else (1.0, 3.0, 10.0)
    tmp = Path(tempfile.mkdtemp(prefix="bench_trainq_"))
    try:
        motions = demo_motions()
        skeleton, look, _ = get_character("tall_long_legs")
        ref = save_performance(tmp / "reference", motions["reference"], skeleton, look, yaw=15.0, size=RENDER,
                               frames=REF_FRAMES)
        gt_iter, gt_track, _ = render_performance(motions["driver"], skeleton, look, yaw=15.0, size=RENDER,
                                                  frames=GT_FRAMES)
        gt_frames = list(gt_iter)
        gt_track = gt_track.to_layout("body15")
        model_path = tmp / "ref_model.pt"
        config = TrainConfig(size=CANVAS, seed=0)
        rows, baseline = [], None
        for budget in budgets:
            t0 = time.perf_counter()
            model_path.unlink(missing_ok=True)
            result = train_reference(ref / "poses.npz", ref / "frames", model_path, config=config, minutes=budget)
            model = load_reference_model(model_path)
            truths = [cut_frame(f, model.canvas) for f in gt_frames]
            if baseline is None:
                refs = [cut_frame(cv2.cvtColor(cv2.imread(str(p)), cv2.COLOR_BGR2RGB), model.canvas)
                        for p in sorted((ref / "frames").glob("*.png"))[::5]]
                background = np.median(np.stack(refs), axis=0).astype(np.uint8)
                baseline = _mean_ssim([background] * len(truths), truths)
            preds = [frame for _, frame in generate_frames(model, gt_track)]
            rows.append(row(f"held-out {GT_FRAMES} frames, {CANVAS}² canvas", f"after {budget:g} min training",
                            _mean_ssim(preds, truths), "SSIM", baseline, "median reference frame (background)",
                            steps=result.steps, wall_s=round(time.perf_counter() - t0, 1)))
        return {"rows": rows, "notes": [
            (f"TrainConfig(size={CANVAS}) defaults otherwise, 1 thread; reference {REF_FRAMES} frames at {RENDER}²; "
            "minutes count training only (train_reference's --minutes), a fresh run for each budget"),
            "steps per minute depend on the machine's other load (the load averages above)",
        ]}
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
