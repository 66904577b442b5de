"""Training the pose-to-frame generator on a reference video (`clone train-ref`).

The data are the reference's frames cut to the canvas and its body15 poses drawn as pose maps on the same
canvas. Each step takes a frame ``t`` with a usable pose and its predecessor ``t-1`` and trains:

- the generator G on ``(pose map t, frame t-1)`` -> frame t. By default the previous frame is G's own frame
  for ``t-1`` made from zeros, as in Everybody Dance Now, so G trains on the kind of input it gets while
  driving; ``prev_source="real"`` feeds the real previous frame instead (teacher forcing), which drifts
  when driving. Either is degraded by a little colour jitter and noise, so that G learns to correct a
  slightly-off previous frame rather than copy it, and dropped to zeros with probability ``prev_dropout``
  (zeros are also what G sees for the first frame of a drive);
- the discriminator D on the consecutive pair ``(pose t-1, pose t, frame t-1, frame t)``: real frames against
  the pair with G's frames, so it judges the step from one frame to the next as well as the frame.

Losses: L1 to the real frame, least-squares GAN, and pix2pixHD's feature matching on D's activations.
Background (``TrainConfig.background``, on by default): a plate estimated from the frames where the person is
elsewhere (:mod:`clone.model.background`); G gives RGB + alpha, its frame is composited over the plate (warped with
the sample) and every loss sees the composite; the plate is stored in the model for `clone drive`.
Augmentation: one small random affine warp (kornia) applied identically to both pose maps and both frames.

The result is ONE reference-model file (see :mod:`clone.model.reference`) holding the generator and, under
``training``, the discriminator, optimisers, random state, step and config, so training can be resumed.

Modules, one job each: :mod:`.config` (settings), :mod:`.data` (reading the reference, frame store, batches),
:mod:`.augment` (random warps, the degraded previous frame), :mod:`.trainer` (networks, losses, one step),
:mod:`.checkpoint` (the model file with its training state), :mod:`.preview` (preview images), :mod:`.state`
(where a run starts, what its steps share) and :mod:`.loop` (:func:`train_reference`).
"""

from clone.train_ref.augment import degrade_previous, random_affines, warp_batch
from clone.train_ref.checkpoint import ReferenceInfo, checkpoint_model, load_resumable, resume_config
from clone.train_ref.config import AugmentConfig, LossConfig, TrainConfig
from clone.train_ref.data import (
    ALIGN_MODES,
    ReferenceData,
    frame_store,
    read_reference,
    reference_codes,
    reference_plate,
    track_summary,
    usable_frames,
)
from clone.train_ref.loop import TrainResult, train_reference
from clone.train_ref.preview import preview_grid, preview_rows, write_png
from clone.train_ref.state import ProgressFn, StepProgress
from clone.train_ref.trainer import Trainer

__all__ = [
    "ALIGN_MODES",
    "AugmentConfig",
    "LossConfig",
    "ProgressFn",
    "ReferenceData",
    "ReferenceInfo",
    "StepProgress",
    "TrainConfig",
    "TrainResult",
    "Trainer",
    "checkpoint_model",
    "degrade_previous",
    "frame_store",
    "load_resumable",
    "preview_grid",
    "preview_rows",
    "random_affines",
    "read_reference",
    "reference_codes",
    "reference_plate",
    "resume_config",
    "track_summary",
    "train_reference",
    "usable_frames",
    "warp_batch",
    "write_png",
]
