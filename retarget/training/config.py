"""The settings of a training run: :class:`TrainConfig` (stored as a plain dict in its checkpoint)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

from retarget.network.model import variant_config
from retarget.network.preprocess import PreprocessConfig
from retarget.training.augment import AugmentConfig
from retarget.training.losses import LossConfig
from retarget.world.camera import CameraSpread

# The inference smoothing of networks trained here, chosen on the validation split (500 cases, clean and with
# detector noise of 0.3 % and 0.6 % of the height, `clone retarget eval --split val --noise`) and on the real
# pairs: no smoothing of the input, whose detector noise the network learned to remove (training corrupts its
# inputs), and a Gaussian of 1 frame on the output. The authors' demo smoothing (2 and 2 frames) damped every
# motion: validation pose error 1.00 -> 0.93, with root 3.26 -> 2.43, range of motion 0.75 -> 0.84, at an output
# jitter on the real tracks still below the driver's (smoothed by 1 frame).
OUR_PREPROCESS = PreprocessConfig(input_sigma=0.0, output_sigma=1.0)


@dataclass(frozen=True)
class TrainConfig:
    """Everything that decides what is learned (defaults: the paper's / the authors' settings).

    Attributes:
        variant: network variant (:data:`retarget.network.model.VARIANTS`).
        window: frames per training window (the longest clip length).
        batch_size: samples per step (each sample has 8 windows).
        lr: Adam learning rate.
        amsgrad: use the AMSGrad variant.
        lr_decay: learning-rate factor per epoch.
        samples_per_epoch: random samples per epoch (validation and a checkpoint follow every epoch).
        val_samples: fixed validation samples (from the "val" split).
        stats_windows: random training windows the normalisation statistics are computed from.
        real_batch_size: real-track windows per step (when real tracks are given).
        real_weight: weight of their self-reconstruction loss.
        seed: seed of every random choice.
        augment: augmentation settings.
        loss: objective settings (see :data:`retarget.training.losses.ABLATIONS`).
        preprocess: canvas and smoothing used at inference (stored in the checkpoint); default
            :data:`OUR_PREPROCESS`, not the authors' demo smoothing.
        cameras: how the camera of a training window is drawn (pitch range, share of perspective cameras
            and their distances); validation keeps the world's cameras.
        body_normalise: bring every character to one skeleton height in training, and every track to it at
            inference, instead of scaling by the image height (the target height is that of the initial
            weights' mean pose, or the median character's; stored in the checkpoint's preprocessing).
        extra_characters: training characters added to the world's, from their own random draws.
        extra_spread: factor on the extra characters' proportion spread.
        frontal_share: share of training samples whose two views are both drawn from the bins within
            ``retarget.world.camera.FRONTAL_YAW`` (45°) of the front, the views of most videos; validation keeps
            every view.
        turn_share: share of training motions given a whole-body turn about the vertical in 3D before
            projection (:mod:`retarget.world.turns`); validation keeps the captured motion.
        turn_range: angles of those turns, degrees, either way.
        splice_share: share of training motions whose torso, arms and head come from another training motion
            (:func:`retarget.world.variations.splice`); validation keeps the captured motion.
        bend_deg: smooth noise of this many degrees on every training motion's upper-body joint angles
            (:func:`retarget.world.variations.bend`; 0: none).
        source_balance: how evenly the motion-capture sources (the top folders of the world's clips, e.g. one
            dataset each) are drawn: a window's chance goes as its source's window count to the power
            ``-source_balance`` (0: every window alike, so a large dataset of everyday motions dominates; 1: every
            source alike; :func:`retarget.training.data.source_weights`).
    """

    variant: str = "full"
    window: int = 64
    batch_size: int = 64
    lr: float = 1e-3
    amsgrad: bool = True
    lr_decay: float = 0.99
    samples_per_epoch: int = 6400
    val_samples: int = 256
    stats_windows: int = 2048
    real_batch_size: int = 16
    real_weight: float = 1.0
    seed: int = 0
    augment: AugmentConfig = field(default_factory=AugmentConfig)
    loss: LossConfig = field(default_factory=LossConfig)
    preprocess: PreprocessConfig = field(default_factory=lambda: OUR_PREPROCESS)
    cameras: CameraSpread = field(default_factory=CameraSpread)
    body_normalise: bool = True
    extra_characters: int = 0
    extra_spread: float = 1.0
    frontal_share: float = 0.0
    turn_share: float = 0.0
    turn_range: tuple[float, float] = (90.0, 360.0)
    splice_share: float = 0.0
    bend_deg: float = 0.0
    source_balance: float = 0.0

    def __post_init__(self) -> None:
        variant_config(self.variant)  # ValueError for an unknown name
        if self.window % 8 or max(self.augment.clip_lengths) > self.window:
            raise ValueError("window must be a multiple of 8 and at least every clip length")
        if self.batch_size <= 0:
            raise ValueError("batch_size must be positive")
        if not 0 <= self.frontal_share <= 1:
            raise ValueError("frontal_share must be a share in [0, 1]")
        if not 0 <= self.turn_share <= 1:
            raise ValueError("turn_share must be a share in [0, 1]")
        if not 0 <= self.turn_range[0] <= self.turn_range[1]:
            raise ValueError("turn_range must be 0 <= low <= high degrees")
        if not 0 <= self.splice_share <= 1:
            raise ValueError("splice_share must be a share in [0, 1]")
        if not 0 <= self.bend_deg <= 45:
            raise ValueError("bend_deg must be in [0, 45] degrees")
        if not 0 <= self.source_balance <= 1:
            raise ValueError("source_balance must be in [0, 1]")

    def to_dict(self) -> dict[str, Any]:
        """Nested plain dict (lists for tuples)."""
        def plain(value: Any) -> Any:
            if isinstance(value, dict):
                return {k: plain(v) for k, v in value.items()}
            return list(value) if isinstance(value, tuple) else value

        return plain(dataclasses.asdict(self))

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> TrainConfig:
        """Inverse of :meth:`to_dict`."""
        nested = {
            "augment": AugmentConfig, "loss": LossConfig, "preprocess": PreprocessConfig, "cameras": CameraSpread,
        }
        values = {k: tuple(v) if isinstance(v, list) else v for k, v in data.items()}
        for key, kind in nested.items():
            if key in values:
                values[key] = kind(**{k: tuple(v) if isinstance(v, list) else v for k, v in values[key].items()})
        return cls(**values)


# The paper's settings; a shared default argument is safe as the config is frozen.
DEFAULT_CONFIG = TrainConfig()
