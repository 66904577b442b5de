"""Training previews: one image, a row per frame: pose map | generated | real, written atomically."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import torch

from clone.model.tensors import to_images
from clone.train_ref.data import ReferenceData
from clone.train_ref.trainer import Trainer
from pose_io.atomic import atomic_file


def preview_grid(trainer: Trainer, data: ReferenceData, rows: np.ndarray) -> np.ndarray:
    """[R*S, 3*S, 3] uint8 grid, one row per frame: pose map | generated | real.

    G gets the real previous frame (no dropout, no jitter), as when driving from a good previous frame; the
    face pass, if the run trains one, refines its faces.
    """
    sample = data.batch(rows)
    with torch.no_grad():
        trainer.g.eval()
        plate = sample["plate"].to(trainer.device) if "plate" in sample else None
        pose = sample["pose_cur"].to(trainer.device)
        exemplar = sample["exemplar_cur"].to(trainer.device) if "exemplar_cur" in sample else None
        fake = trainer.generate(pose, sample["frame_prev"].to(trainer.device), plate, exemplar)
        trainer.g.train()
        if trainer.face_pass is not None and "face" in sample:
            trainer.face_pass.eval()
            fake = trainer.refine_faces(fake, pose, sample["face"].to(trainer.device))
            trainer.face_pass.train()
    cols = [to_images(sample["pose_cur"]), to_images(fake), to_images(sample["frame_cur"])]
    return np.concatenate([np.concatenate(c, axis=0) for c in cols], axis=1)


def write_png(image: np.ndarray, path: Path) -> None:
    """Write an RGB uint8 image atomically."""
    with atomic_file(path, overwrite=True) as tmp:
        ok, buf = cv2.imencode(".png", cv2.cvtColor(image, cv2.COLOR_RGB2BGR))
        if not ok:
            raise RuntimeError(f"could not encode {path}")
        tmp.write_bytes(buf.tobytes())


def preview_rows(indices: np.ndarray, count: int = 4) -> np.ndarray:
    """Up to ``count`` of the frame ``indices``, evenly spread: the rows of every preview of a run."""
    picks = np.linspace(0, len(indices) - 1, num=min(count, len(indices))).round().astype(int)
    return indices[np.unique(picks)]
