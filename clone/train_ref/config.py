"""Settings of a reference-training run: augmentation, loss weights and everything else but paths and device."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

from clone.choices import PrevSource
from clone.model.background import PlateConfig
from clone.model.networks import DiscriminatorConfig, GeneratorConfig, default_depth
from clone.model.reference import POSE_LAYOUTS


@dataclass(frozen=True)
class AugmentConfig:
    """Random changes applied to each training sample.

    Attributes:
        rotation_deg: largest rotation, degrees (same warp for pose maps and frames).
        scale: largest relative zoom in or out.
        translate: largest shift as a fraction of the canvas.
        prev_jitter: largest relative brightness/contrast/saturation change of the previous-frame input.
        prev_noise: standard deviation of Gaussian noise on the previous-frame input ([-1, 1] units).
        pose_jitter: standard deviation of Gaussian noise added to every joint of the pose maps G and D see (not
            to the frames), as a share of the reference's standing height (0: none): the same frame under
            slightly different poses, so that poses the reference never made map to her look.
        mirror: share of the samples flipped left-right (frames, plate and pose maps, left and right joints
            swapped): a reference who turns one way is also seen turning the other, her left arm's poses also on
            her right. Only for outfits and backgrounds that look alike mirrored (no writing, no one-sided cut).
        person_crop: train on a window of the canvas around the person (her joints' extent and a margin,
            each side a multiple of the generator's stride, at least half the canvas) instead of the whole
            canvas, but for one step in five (``augment.WHOLE_CANVAS_SHARE``): the steps skip background the plate
            already gives (1.3-1.6x the steps on the two fashion videos of ``../shared/real``). Driving still runs
            on the whole canvas, whose instance-norm statistics differ from a window's: on the demo's checked
            shirt the texture came out washed, so it is off by default.
        exemplar_drop: share of the samples (with exemplars) whose exemplar is blacked out along one limb chosen
            at random (:data:`clone.model.exemplar.LIMBS`), as driving blacks out a limb that strays from the pose
            asked: the generator learns to paint a limb the exemplar does not show (raised arms the reference
            never made).
    """

    rotation_deg: float = 3.0
    scale: float = 0.05
    translate: float = 0.03
    prev_jitter: float = 0.1
    prev_noise: float = 0.03
    pose_jitter: float = 0.0
    mirror: float = 0.0
    person_crop: bool = False
    exemplar_drop: float = 0.25


@dataclass(frozen=True)
class LossConfig:
    """Loss weights: pix2pix's L1 weight, pix2pixHD's feature-matching weight, GAN weight 1, and the terms of
    :mod:`clone.train_ref.losses`.

    Attributes:
        l1: weight of the per-pixel L1 to the real frame.
        gan: weight of the least-squares GAN loss.
        feature_matching: weight of pix2pixHD's feature matching on D's activations.
        person: extra weight of the person's pixels in every reconstruction term (0: all pixels alike).
        face: extra weight of the face's pixels (a disc around the face points of body31 maps) on top of the
            person's.
        ssim: weight of ``1 - SSIM`` to the real frame.
        laplacian: weight of the L1 between Laplacian pyramids.
        face_gan: weight of a second PatchGAN's loss on face crops (training only; body31 pose maps), with
            feature matching at ``feature_matching`` times it.
    """

    l1: float = 100.0
    gan: float = 1.0
    feature_matching: float = 10.0
    person: float = 0.0
    face: float = 0.0
    ssim: float = 0.0
    laplacian: float = 0.0
    face_gan: float = 0.0


@dataclass(frozen=True)
class TrainConfig:
    """Everything that decides a training run except paths, device and budget.

    Attributes:
        size: canvas size in pixels (power of two).
        canvas_mode: ``crop`` around the performer or ``full`` frame letterboxed.
        canvas_margin: crop margin as a fraction of the performer's height.
        base_channels: generator width; None picks 16 for canvases of 256² and more, 32 below.
        upsample: generator decoder upsampling (see ``GeneratorConfig``).
        depth: generator depth; None picks a 4x4 bottleneck for ``size``.
        disc_channels: discriminator width.
        disc_layers: discriminator stride-2 layers.
        batch_size: samples per step.
        lr: Adam learning rate of both networks.
        init_lr: the learning rate instead of ``lr`` for a run started from another model's networks
            (``init`` of :func:`clone.train_ref.train_reference`, the shipped prior by default); None: ``lr``.
        lr_decay_from: share of a run after which the learning rate falls linearly to 0 at its end, as pix2pix
            decays it over its second half (1: constant). A run's length is its budget, whichever ends it
            first: ``--minutes`` of training in this call (a resumed call is a run of its own), or the steps
            in all it was asked for (counted from the model's first, so a run resumed to N steps equals one
            run of N).
        beta1: Adam beta1 (pix2pix uses 0.5).
        prev_dropout: probability that the previous-frame input is zeros.
        prev_source: ``real`` previous frames or G's own (``generated``), see
            :meth:`clone.train_ref.Trainer.previous_input`; the plain name is accepted too.
        temporal: give G the previous frame at all.
        background: estimate the reference's background plate (:mod:`clone.model.background`) and let G composite
            its frames over it (RGB + alpha); the plate is stored in the model.
        plate_input: G also sees the plate as input channels (with ``background``).
        plate: how the plate is estimated.
        face_pass: train a face pass beside the generator (:mod:`clone.model.face`: a small U-Net on the face's
            crop adding a residual, as Everybody Dance Now's face GAN, with its own discriminator), stored in the
            model and run by `clone drive`. None: on from 128² canvases up. Body31 pose maps only (off with
            body15); a reference whose poses have no face points trains none.
        exemplar: G also gets an exemplar (:mod:`clone.model.exemplar`): the reference's own frame nearest in
            pose, laid onto the pose asked, as three more input channels; the bank of frames it comes from is
            stored in the model. None: on from 128² canvases up (fixed in ``__post_init__``).
        pose_layout: what the pose maps show: ``body31`` (body15 with the face, hands and feet, front and back
            told apart, :mod:`clone.model.detail_map`) or ``body15`` (the skeleton alone, as models before it).
        min_visible_joints: frames whose pose has fewer visible body15 joints are skipped.
        steps: default number of steps when neither steps nor minutes are given.
        preview_every: steps between preview images.
        save_every_s: seconds between checkpoints.
        seed: random seed of the run.
        augment: augmentation settings.
        loss: loss weights.
    """

    size: int = 128
    canvas_mode: str = "crop"
    canvas_margin: float = 0.25
    # None: 16 from 256² up, else 32 (fixed in __post_init__, so a stored run keeps its width). At 256² on one
    # CPU thread 16 runs the generator 2.1-2.8x faster and, at equal CPU minutes of training, scored SSIM 0.949
    # against 32's 0.954; at 128² it cost more (0.962 against 0.969, 0.835 against 0.861 on the person's crop).
    base_channels: int | None = None
    # Not pix2pix's transposed convolutions: at the few thousand steps a CPU budget allows they still show
    # checkerboard patterns; nearest + 3x3 conv gave +1 dB PSNR at equal steps on synthetic performers.
    upsample: str = "nearest"
    depth: int | None = None
    disc_channels: int = 32
    disc_layers: int = 3
    batch_size: int = 1
    # Chosen on real footage (docs/cloning.md, "Real footage"): lr 5e-4 falling to 0 over the run's second half
    # against a constant 2e-4, 3 minutes 0.895 / 23.9 dB against 0.879 / 22.6 (person box), 10 minutes 0.910 /
    # 24.7 dB against 0.903 / 24.2.
    lr: float = 5e-4
    # Chosen on real footage (docs/cloning.md, "A generator prior"): from the shipped prior, 3 minutes on one
    # thread, person box SSIM 0.847 / 0.858 / 0.868 at 3e-4 / 5e-4 / 1e-3 on the second fashion video.
    init_lr: float | None = 1e-3
    lr_decay_from: float = 0.5
    beta1: float = 0.5
    prev_dropout: float = 0.3
    # Teacher forcing with real previous frames drifted by 3 dB PSNR when driving on its own output.
    prev_source: PrevSource = PrevSource.GENERATED
    temporal: bool = True
    background: bool = True
    plate_input: bool = False
    plate: PlateConfig = field(default_factory=PlateConfig)
    # None: on from 256² up with body31 maps, where it was measured on real footage (docs/cloning.md, "The face
    # pass": 10 minutes, face SSIM 0.867 against 0.692), off below (fixed in __post_init__).
    face_pass: bool | None = None
    # None: on from 128² up, where it was measured on real footage (docs/cloning.md, "Exemplars": 3 minutes, one
    # thread, person box 0.885 / 25.3 dB against 0.868 / 24.9 and 0.926 / 25.8 against 0.909 / 24.6 at 256² from
    # the prior, 0.928 / 28.0 against 0.892 / 25.9 at 128² from random weights).
    exemplar: bool | None = None
    pose_layout: str = "body31"
    min_visible_joints: int = 10
    steps: int = 2000
    preview_every: int = 250
    save_every_s: float = 120.0
    seed: int = 0
    augment: AugmentConfig = field(default_factory=AugmentConfig)
    loss: LossConfig = field(default_factory=LossConfig)

    def __post_init__(self) -> None:
        # A misspelt name must not fall through to teacher forcing (the trainer only tests for "generated").
        try:
            source = PrevSource(self.prev_source)
        except ValueError:
            valid = ", ".join(s.value for s in PrevSource)
            raise ValueError(f"unknown prev_source {self.prev_source!r}; valid: {valid}") from None
        object.__setattr__(self, "prev_source", source)
        if self.pose_layout not in POSE_LAYOUTS:
            raise ValueError(f"unknown pose_layout {self.pose_layout!r}; valid: {', '.join(POSE_LAYOUTS)}")
        if self.face_pass is None:
            object.__setattr__(self, "face_pass", self.size >= 128)
        if self.pose_layout == "body15":  # no face points to find the face by
            object.__setattr__(self, "face_pass", False)
        if self.base_channels is None:
            object.__setattr__(self, "base_channels", 16 if self.size >= 256 else 32)
        if self.exemplar is None:
            object.__setattr__(self, "exemplar", self.size >= 128)
        if not 0.0 <= self.lr_decay_from <= 1.0:
            raise ValueError(f"lr_decay_from must be a share in [0, 1], got {self.lr_decay_from!r}")

    def lr_factor(self, progress: float) -> float:
        """The learning rate's factor at ``progress`` (0 at a run's start, 1 at its end): 1 until
        ``lr_decay_from``, then falling linearly to 0."""
        if progress <= self.lr_decay_from:
            return 1.0
        return max(0.0, (1.0 - progress) / (1.0 - self.lr_decay_from))

    @property
    def uses_faces(self) -> bool:
        """Whether a loss or the face pass needs each sample's face disc."""
        return bool(self.loss.face or self.loss.face_gan or self.face_pass)

    def generator_config(self) -> GeneratorConfig:
        """The generator this run trains."""
        depth = self.depth if self.depth is not None else default_depth(self.size)
        return GeneratorConfig(
            in_channels=(6 if self.temporal else 3) + (3 if self.exemplar else 0), base_channels=self.base_channels, depth=depth,
            upsample=self.upsample, alpha=self.background, plate_input=self.background and self.plate_input,
            exemplar=bool(self.exemplar),
        )

    def discriminator_config(self) -> DiscriminatorConfig:
        """The discriminator this run trains."""
        return DiscriminatorConfig(base_channels=self.disc_channels, num_layers=self.disc_layers)

    def to_dict(self) -> dict[str, Any]:
        """Plain nested dict (stored in the model file, so the enum is stored as its name)."""
        data = asdict(self)
        data["prev_source"] = self.prev_source.value
        return data

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> TrainConfig:
        """Inverse of :meth:`to_dict`; ``data`` is left unchanged.

        Raises:
            TypeError, KeyError: ``data`` has unknown or missing entries.
            ValueError: ``data`` names an unknown ``prev_source``.
        """
        data = dict(data)
        augment = AugmentConfig(**data.pop("augment"))
        loss = LossConfig(**data.pop("loss"))
        plate = PlateConfig(**data.pop("plate", {}))
        # Runs stored before the background plate trained without one.
        data.setdefault("background", False)
        # Runs stored before detailed pose maps drew body15.
        data.setdefault("pose_layout", "body15")
        # Runs stored before the learning-rate schedule kept it constant.
        data.setdefault("lr_decay_from", 1.0)
        # Runs stored before the face pass had none.
        data.setdefault("face_pass", False)
        # Runs stored before exemplars had none.
        data.setdefault("exemplar", False)
        return cls(**data, augment=augment, loss=loss, plate=plate)
