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
Augmentation: one small random affine warp (kornia) applied identically to both pose maps and both frames.

The result is one reference-model file (see :mod:`clone.reference_model`); the discriminator, optimisers
and step go to ``<model>.state`` so training can be resumed.
"""

from __future__ import annotations

import contextlib
import logging
import os
import tempfile
import time
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import cv2
import numpy as np
import torch
import torch.nn.functional as F
from torch import Tensor

from clone.canvas import choose_canvas, cut_frame, image_to_canvas, render_pose_map
from clone.networks import (
    DiscriminatorConfig,
    GeneratorConfig,
    PatchDiscriminator,
    UNetGenerator,
    build_discriminator,
    build_generator,
    default_depth,
    discriminator_input,
    feature_matching_loss,
    generator_input,
    lsgan_loss,
)
from clone.reference_model import (
    FORMAT_VERSION,
    LAYOUT,
    STATE_KIND,
    ReferenceModel,
    file_sha256,
    load_checkpoint_dict,
    load_reference_model,
    preview_path,
    save_reference_model,
    state_path,
)
from pose_io.atomic import atomic_file
from pose_io.errors import InputError
from pose_io.layouts import get_layout
from pose_io.track import PoseTrack
from retarget.global_scale import ScaleStats, scale_stats

if TYPE_CHECKING:
    from pose_io.video import Frames

log = logging.getLogger(__name__)

ALIGN_MODES = ("exact", "trim")
# Frames are kept in memory up to this many bytes, beyond that in a temporary memory-mapped file.
_IN_MEMORY_BYTES = 1 << 30


@dataclass(frozen=True)
class AugmentConfig:
    """Random changes applied to each training sample.

    Attributes:
        rotation_deg: largest rotation, degrees (same warp for pose maps and frames).
        scale: largest relative zoom in or out.
        translate: largest shift as a fraction of the canvas.
        prev_jitter: largest relative brightness/contrast/saturation change of the previous-frame input.
        prev_noise: standard deviation of Gaussian noise on the previous-frame input ([-1, 1] units).
    """

    rotation_deg: float = 3.0
    scale: float = 0.05
    translate: float = 0.03
    prev_jitter: float = 0.1
    prev_noise: float = 0.03


@dataclass(frozen=True)
class LossConfig:
    """Loss weights: pix2pix's L1 weight, pix2pixHD's feature-matching weight, GAN weight 1."""

    l1: float = 100.0
    gan: float = 1.0
    feature_matching: float = 10.0


@dataclass(frozen=True)
class TrainConfig:
    """Everything that decides a training run except paths, device and budget.

    Attributes:
        size: canvas size in pixels (power of two).
        canvas_mode: ``crop`` around the performer or ``full`` frame letterboxed.
        canvas_margin: crop margin as a fraction of the performer's height.
        base_channels: generator width.
        upsample: generator decoder upsampling (see ``GeneratorConfig``).
        depth: generator depth; None picks a 4x4 bottleneck for ``size``.
        disc_channels: discriminator width.
        disc_layers: discriminator stride-2 layers.
        batch_size: samples per step.
        lr: Adam learning rate of both networks.
        beta1: Adam beta1 (pix2pix uses 0.5).
        prev_dropout: probability that the previous-frame input is zeros.
        prev_source: ``real`` previous frames or G's own (``generated``), see :meth:`Trainer.previous_input`.
        temporal: give G the previous frame at all.
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
    base_channels: int = 32
    # Not pix2pix's transposed convolutions: at the few thousand steps a CPU budget allows they still show
    # checkerboard patterns; nearest + 3x3 conv gave +1 dB PSNR at equal steps on synthetic performers.
    upsample: str = "nearest"
    depth: int | None = None
    disc_channels: int = 32
    disc_layers: int = 3
    batch_size: int = 1
    lr: float = 2e-4
    beta1: float = 0.5
    prev_dropout: float = 0.3
    # Teacher forcing with real previous frames drifted by 3 dB PSNR when driving on its own output.
    prev_source: str = "generated"
    temporal: bool = True
    min_visible_joints: int = 10
    steps: int = 2000
    preview_every: int = 250
    save_every_s: float = 120.0
    seed: int = 0
    augment: AugmentConfig = field(default_factory=AugmentConfig)
    loss: LossConfig = field(default_factory=LossConfig)

    def generator_config(self) -> GeneratorConfig:
        depth = self.depth if self.depth is not None else default_depth(self.size)
        return GeneratorConfig(
            in_channels=6 if self.temporal else 3, base_channels=self.base_channels, depth=depth,
            upsample=self.upsample,
        )

    def discriminator_config(self) -> DiscriminatorConfig:
        return DiscriminatorConfig(base_channels=self.disc_channels, num_layers=self.disc_layers)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


@dataclass(frozen=True)
class TrainResult:
    """What a training run did."""

    model_path: Path
    preview_path: Path
    steps: int
    steps_this_run: int
    seconds: float
    frames: int
    usable_frames: int
    skipped_frames: int
    has_codes: bool
    interrupted: bool
    last_losses: dict[str, float]


# ------------------------------------------------------------------------------------------------ data


def to_tensor(images: np.ndarray) -> Tensor:
    """[B, H, W, 3] uint8 RGB -> [B, 3, H, W] float in [-1, 1]."""
    t = torch.from_numpy(np.ascontiguousarray(images)).permute(0, 3, 1, 2)  # [B, 3, H, W]
    return t.float().div_(127.5).sub_(1.0)


def to_images(tensor: Tensor) -> np.ndarray:
    """[B, 3, H, W] float in [-1, 1] -> [B, H, W, 3] uint8 RGB."""
    x = ((tensor.detach().float().clamp(-1, 1) + 1.0) * 127.5).round().to(torch.uint8)
    return x.permute(0, 2, 3, 1).cpu().numpy()  # [B, H, W, 3]


def usable_frames(track: PoseTrack, min_visible: int) -> np.ndarray:
    """[T] bool: frames with at least ``min_visible`` visible joints."""
    return (~track.missing).sum(axis=1) >= min_visible


class ReferenceData:
    """The reference's frames on the canvas and its poses in canvas pixels.

    Attributes:
        frames: [N, S, S, 3] uint8 RGB (in memory or memory-mapped).
        joints: [N, J, 2] float32 canvas pixels, NaN where missing.
        usable: [N] bool, frames trained on.
        size: S.
    """

    def __init__(self, frames: np.ndarray, joints: np.ndarray, usable: np.ndarray, size: int) -> None:
        self.frames = frames
        self.joints = joints
        self.usable = usable
        self.size = size
        self.layout = get_layout(LAYOUT)
        self.indices = np.flatnonzero(usable)

    def pose_map(self, i: int) -> np.ndarray:
        """[S, S, 3] uint8 pose map of frame ``i`` (black for i < 0)."""
        if i < 0:
            return np.zeros((self.size, self.size, 3), dtype=np.uint8)
        return render_pose_map(self.joints[i], self.size, self.layout)

    def batch(self, idx: np.ndarray) -> dict[str, Tensor]:
        """Tensors for frames ``idx`` and their predecessors.

        Returns:
            ``pose_prev``, ``pose_cur``, ``frame_prev``, ``frame_cur``: [B, 3, S, S] in [-1, 1] (the previous
            frame of frame 0 is zeros); ``has_prev``: [B] bool.
        """
        prev = idx - 1
        zero = np.zeros((self.size, self.size, 3), dtype=np.uint8)
        has_prev = torch.from_numpy(prev >= 0)
        frame_prev = to_tensor(np.stack([self.frames[p] if p >= 0 else zero for p in prev]))
        frame_prev[~has_prev] = 0.0
        return {
            "pose_prev": to_tensor(np.stack([self.pose_map(int(p)) for p in prev])),
            "pose_cur": to_tensor(np.stack([self.pose_map(int(i)) for i in idx])),
            "frame_prev": frame_prev,
            "frame_cur": to_tensor(np.stack([self.frames[i] for i in idx])),
            "has_prev": has_prev,
        }


@contextlib.contextmanager
def frame_store(count: int, size: int) -> Iterator[np.ndarray]:
    """A [count, size, size, 3] uint8 array: in memory when small, else a temporary memory-mapped file."""
    nbytes = count * size * size * 3
    if nbytes <= _IN_MEMORY_BYTES:
        yield np.zeros((count, size, size, 3), dtype=np.uint8)
        return
    with tempfile.TemporaryDirectory(prefix="clone2d-frames-") as tmp:
        log.info("keeping %d frames (%.1f GiB) in a memory-mapped file", count, nbytes / 2**30)
        arr = np.lib.format.open_memmap(os.path.join(tmp, "frames.npy"), mode="w+", dtype=np.uint8,
                                        shape=(count, size, size, 3))
        try:
            yield arr
        finally:
            del arr


def read_reference(
    poses_path: str | os.PathLike, frames_path: str | os.PathLike, align: str = "exact"
) -> tuple[PoseTrack, Frames, int]:
    """Open the reference's poses and frames and check that they belong together.

    Args:
        poses_path: any pose track ``pose_io`` reads.
        frames_path: a video or a folder of images.
        align: ``exact`` (counts must agree) or ``trim`` (use the common prefix).

    Returns:
        ``(track in body15 with the frames' image size, frame stream, frame count to use)``.
    """
    from pose_io.readers import read_detections, track_from_detections
    from pose_io.video import read_frames

    if align not in ALIGN_MODES:
        raise InputError(f"unknown --align {align!r}; valid: {', '.join(ALIGN_MODES)}")
    frames = read_frames(frames_path)
    detections = read_detections(poses_path)
    if detections.image_size is not None and tuple(detections.image_size) != tuple(frames.size):
        raise InputError(
            f"{poses_path}: poses are for {detections.image_size[0]}x{detections.image_size[1]} frames, "
            f"{frames_path} has {frames.size[0]}x{frames.size[1]}"
        )
    track = track_from_detections(detections, fps=None, image_size=tuple(frames.size))
    if frames.kind == "video":
        track = track.replace(fps=frames.fps)
    track = track.to_layout(LAYOUT)
    n_frames, n_poses = frames.num_frames, track.num_frames
    if n_frames != n_poses:
        if align != "trim":
            raise InputError(
                f"{poses_path} has {n_poses} poses but {frames_path} has {n_frames} frames; "
                f"pass --align trim to use the first {min(n_frames, n_poses)} of each"
            )
        log.warning("using the first %d frames and poses (%d poses, %d frames)", min(n_frames, n_poses),
                    n_poses, n_frames)
    count = min(n_frames, n_poses)
    return track.frames(0, count), frames, count


def track_summary(track: PoseTrack, usable: np.ndarray) -> dict[str, Any]:
    """Plain-data summary of the reference's poses for the model file."""
    layout = track.joint_layout
    bones = {}
    for a, b in layout.limbs:
        d = np.linalg.norm(track.joint(a) - track.joint(b), axis=-1)
        d = d[np.isfinite(d)]
        bones[f"{a}-{b}"] = float(np.median(d)) if len(d) else float("nan")
    return {
        "frames": track.num_frames,
        "usable_frames": int(usable.sum()),
        "skipped_frames": int((~usable).sum()),
        "fps": track.fps,
        "image_size": list(track.image_size),
        "layout": track.layout,
        "visible_fraction": (1.0 - track.missing.mean(axis=0)).astype(np.float32),
        "median_bone_lengths": bones,
    }


# ------------------------------------------------------------------------------------------------ augmentation


def random_affines(batch: int, size: int, cfg: AugmentConfig, generator: torch.Generator) -> Tensor:
    """[B, 2, 3] pixel affine matrices: small rotation and zoom about the centre, plus a shift."""
    u = torch.rand(batch, 4, generator=generator) * 2.0 - 1.0  # [B, 4] in [-1, 1]
    angle = torch.deg2rad(u[:, 0] * cfg.rotation_deg)
    scale = 1.0 + u[:, 1] * cfg.scale
    shift = u[:, 2:] * cfg.translate * size  # [B, 2]
    c = (size - 1) / 2.0
    cos, sin = torch.cos(angle) * scale, torch.sin(angle) * scale
    m = torch.zeros(batch, 2, 3)
    m[:, 0, 0], m[:, 0, 1] = cos, -sin
    m[:, 1, 0], m[:, 1, 1] = sin, cos
    m[:, 0, 2] = c - cos * c + sin * c + shift[:, 0]
    m[:, 1, 2] = c - sin * c - cos * c + shift[:, 1]
    return m


def warp_batch(sample: dict[str, Tensor], matrices: Tensor) -> dict[str, Tensor]:
    """Warp pose maps and frames of a sample with the same [B, 2, 3] matrices (kornia).

    Pose maps are padded with black (-1), frames by repeating their border.
    """
    from kornia.geometry.transform import warp_affine

    size = sample["pose_cur"].shape[-1]
    m = matrices.to(sample["pose_cur"].device)
    out = dict(sample)
    poses = torch.cat([sample["pose_prev"], sample["pose_cur"]], dim=1) + 1.0  # [B, 6, S, S], black = 0
    poses = warp_affine(poses, m, (size, size), padding_mode="zeros", align_corners=True) - 1.0
    out["pose_prev"], out["pose_cur"] = poses[:, :3], poses[:, 3:]
    frames = torch.cat([sample["frame_prev"], sample["frame_cur"]], dim=1)  # [B, 6, S, S]
    frames = warp_affine(frames, m, (size, size), padding_mode="border", align_corners=True)
    out["frame_prev"], out["frame_cur"] = frames[:, :3], frames[:, 3:]
    out["frame_prev"] = torch.where(sample["has_prev"].to(m.device)[:, None, None, None], out["frame_prev"], 0.0)
    return out


def degrade_previous(
    prev: Tensor, has_prev: Tensor, cfg: AugmentConfig, dropout: float, generator: torch.Generator
) -> Tensor:
    """The previous-frame input as G gets it: colour-jittered, noisy, sometimes zeros.

    Args:
        prev: [B, 3, S, S] in [-1, 1].
        has_prev: [B] bool; samples without a previous frame get exact zeros, as the first driven frame does.
        cfg: augmentation settings.
        dropout: probability of replacing a sample's previous frame by zeros.
        generator: CPU random generator.

    Returns:
        [B, 3, S, S].
    """
    from kornia.enhance import adjust_brightness, adjust_contrast, adjust_saturation

    b = prev.shape[0]
    u = (torch.rand(b, 3, generator=generator) * 2.0 - 1.0).to(prev.device)  # [B, 3]
    x = (prev + 1.0) / 2.0  # [0, 1]
    x = adjust_brightness(x, u[:, 0] * cfg.prev_jitter)
    x = adjust_contrast(x, 1.0 + u[:, 1] * cfg.prev_jitter)
    x = adjust_saturation(x, 1.0 + u[:, 2] * cfg.prev_jitter)
    x = x.clamp(0, 1) * 2.0 - 1.0
    noise = torch.randn(prev.shape, generator=generator).to(prev.device) * cfg.prev_noise
    keep = (torch.rand(b, generator=generator) >= dropout).to(prev.device) & has_prev.to(prev.device)
    keep = keep[:, None, None, None]
    return torch.where(keep, x + noise, torch.zeros_like(x))


# ------------------------------------------------------------------------------------------------ trainer


class Trainer:
    """Generator, discriminator, optimisers and one training step.

    Args:
        config: the run's settings.
        device: where the networks live.
        generator: an existing generator (resuming); a fresh one when None.
    """

    def __init__(self, config: TrainConfig, device: torch.device, generator: UNetGenerator | None = None) -> None:
        self.config = config
        self.device = device
        self.g = (generator or build_generator("unet", config.generator_config())).to(device).train()
        self.d: PatchDiscriminator = build_discriminator("patch", config.discriminator_config()).to(device).train()
        betas = (config.beta1, 0.999)
        self.opt_g = torch.optim.Adam(self.g.parameters(), lr=config.lr, betas=betas)
        self.opt_d = torch.optim.Adam(self.d.parameters(), lr=config.lr, betas=betas)
        self.step_count = 0

    def generate(self, pose: Tensor, prev: Tensor) -> Tensor:
        """G's frame for [B, 3, S, S] pose maps and previous frames."""
        return self.g(generator_input(pose, prev) if self.config.temporal else pose)

    def previous_input(self, sample: dict[str, Tensor], generator: torch.Generator) -> tuple[Tensor, Tensor]:
        """What G gets as the previous frame, and the previous frame D sees in a fake pair.

        ``prev_source == "real"``: the real previous frame, degraded; D's fake pair starts from the real one.
        ``prev_source == "generated"``: G's own frame for ``t-1`` made from zeros (no gradient), degraded, as
        in Everybody Dance Now; D's fake pair is then entirely generated.

        Returns:
            ``(G's previous-frame input, D's previous frame)``, both [B, 3, S, S].
        """
        cfg = self.config
        if cfg.prev_source == "generated":
            with torch.no_grad():
                prev = self.generate(sample["pose_prev"], torch.zeros_like(sample["frame_prev"]))
        else:
            prev = sample["frame_prev"]
        prev = torch.where(sample["has_prev"][:, None, None, None], prev, 0.0)
        return degrade_previous(prev, sample["has_prev"], cfg.augment, cfg.prev_dropout, generator), prev

    def train_step(self, sample: dict[str, Tensor], prev_input: Tensor, fake_prev: Tensor | None = None
                   ) -> dict[str, float]:
        """One update of G and then of D.

        Args:
            sample: the (augmented) batch of :meth:`ReferenceData.batch`, on the device.
            prev_input: [B, 3, S, S] what G gets as the previous frame.
            fake_prev: [B, 3, S, S] previous frame of D's fake pairs (default: the real one).

        Returns:
            Loss values.
        """
        w = self.config.loss
        real = sample["frame_cur"]
        fake = self.generate(sample["pose_cur"], prev_input)  # [B, 3, S, S]
        pair = (sample["pose_prev"], sample["pose_cur"], sample["frame_prev"])
        real_in = discriminator_input(*pair, real)  # [B, 12, S, S]
        fake_pair = (sample["pose_prev"], sample["pose_cur"], sample["frame_prev"] if fake_prev is None else fake_prev)

        self.d.requires_grad_(False)
        fake_feats = self.d(discriminator_input(*fake_pair, fake))
        with torch.no_grad():
            real_feats = self.d(real_in)
        l1 = F.l1_loss(fake, real)
        gan = lsgan_loss(fake_feats[-1], True)
        fm = feature_matching_loss(fake_feats, real_feats)
        loss_g = w.l1 * l1 + w.gan * gan + w.feature_matching * fm
        self.opt_g.zero_grad(set_to_none=True)
        loss_g.backward()
        self.opt_g.step()

        self.d.requires_grad_(True)
        d_real = self.d(real_in)[-1]
        d_fake = self.d(discriminator_input(*fake_pair, fake.detach()))[-1]
        loss_d = 0.5 * (lsgan_loss(d_real, True) + lsgan_loss(d_fake, False))
        self.opt_d.zero_grad(set_to_none=True)
        loss_d.backward()
        self.opt_d.step()
        self.step_count += 1
        return {"l1": l1.item(), "gan": gan.item(), "fm": fm.item(), "d": loss_d.item()}

    def state_dict(self) -> dict[str, Any]:
        return {
            "discriminator": {"name": "patch", "config": self.d.config.to_dict(), "state_dict": self.d.state_dict()},
            "opt_g": self.opt_g.state_dict(),
            "opt_d": self.opt_d.state_dict(),
            "step": self.step_count,
        }

    def load_state_dict(self, state: dict[str, Any]) -> None:
        self.d.load_state_dict(state["discriminator"]["state_dict"])
        self.opt_g.load_state_dict(state["opt_g"])
        self.opt_d.load_state_dict(state["opt_d"])
        self.step_count = int(state["step"])


# ------------------------------------------------------------------------------------------------ previews


def preview_grid(trainer: Trainer, data: ReferenceData, rows: np.ndarray) -> np.ndarray:
    """[R*S, 3*S, 3] uint8 grid, one row per frame: pose map | generated | real.

    G gets the real previous frame (no dropout, no jitter), as when driving from a good previous frame.
    """
    sample = data.batch(rows)
    with torch.no_grad():
        trainer.g.eval()
        fake = trainer.generate(sample["pose_cur"].to(trainer.device), sample["frame_prev"].to(trainer.device))
        trainer.g.train()
    cols = [to_images(sample["pose_cur"]), to_images(fake), to_images(sample["frame_cur"])]
    return np.concatenate([np.concatenate(c, axis=0) for c in cols], axis=1)


def write_png(image: np.ndarray, path: Path) -> None:
    """Write an RGB uint8 image atomically."""
    with atomic_file(path, overwrite=True) as tmp:
        ok, buf = cv2.imencode(".png", cv2.cvtColor(image, cv2.COLOR_RGB2BGR))
        if not ok:
            raise RuntimeError(f"could not encode {path}")
        tmp.write_bytes(buf.tobytes())


# ------------------------------------------------------------------------------------------------ codes


def reference_codes(
    track: PoseTrack, weights: str | os.PathLike | None
) -> tuple[dict[str, Any] | None, str | None, str | None]:
    """The retargeting network's codes of the reference: ``(codes dict, weights SHA-256, weights path)``.

    An explicitly given ``weights`` file must load and encode the track; without one, the shipped weights are
    used when present, and otherwise no codes are stored (training still works; drive then needs --weights
    for ``--method retarget``).
    """
    from retarget.api import PACKAGED_WEIGHTS, load_retargeter

    if weights is None and not PACKAGED_WEIGHTS.is_file():
        log.warning("no retargeting weights are shipped; storing no reference codes (pass --weights to store them)")
        return None, None, None
    path = Path(weights) if weights is not None else PACKAGED_WEIGHTS
    try:
        codes = load_retargeter(path, device="cpu").reference_codes(track)
    except InputError as exc:
        if weights is not None:
            raise
        log.warning("reference codes: %s; storing none", exc)
        return None, None, None
    return codes.to_dict(), file_sha256(path), str(path.resolve())


# ------------------------------------------------------------------------------------------------ training


@dataclass
class TrainProgress:
    """Where a run stands, passed to the progress callback after every step (and every frame read).

    While ``phase`` is ``"reading"``, ``step`` counts frames read out of ``total``.
    """

    phase: str
    step: int
    total: int | None
    elapsed: float
    limit_s: float | None
    losses: dict[str, float]


ProgressFn = Callable[[TrainProgress], None]


def _preview_rows(indices: np.ndarray, count: int = 4) -> np.ndarray:
    picks = np.linspace(0, len(indices) - 1, num=min(count, len(indices))).round().astype(int)
    return indices[np.unique(picks)]


def train_reference(
    poses_path: str | os.PathLike,
    frames_path: str | os.PathLike,
    out: str | os.PathLike = "ref_model.pt",
    *,
    config: TrainConfig | None = None,
    steps: int | None = None,
    minutes: float | None = None,
    device: torch.device | str = "cpu",
    resume: bool = False,
    overwrite: bool = False,
    align: str = "exact",
    weights: str | os.PathLike | None = None,
    progress: ProgressFn | None = None,
) -> TrainResult:
    """Train (or continue training) a reference model.

    Args:
        poses_path: the reference's poses (any format ``pose_io`` reads).
        frames_path: the reference's video or image folder, frame ``t`` matching pose ``t``.
        out: the model file to write.
        config: settings of a new run (default ``TrainConfig()``). When resuming, the stored run's settings
            apply; of ``config`` only ``batch_size``, ``preview_every`` and ``save_every_s`` are taken, and
            a different ``size`` is an error.
        steps: stop when the model has been trained this many steps in total.
        minutes: stop after this many minutes of training in this run (reading the frames not counted).
        device: where to train.
        resume: continue the model at ``out`` with its ``.state`` file.
        overwrite: replace an existing model at ``out`` with a new one.
        align: ``exact`` or ``trim`` (see :func:`read_reference`).
        weights: retargeting weights for the reference codes (default: the shipped ones, if present).
        progress: called after every step.

    Returns:
        What was done.
    """
    out = Path(out)
    device = torch.device(device)
    if resume and overwrite:
        raise InputError("--resume and --overwrite exclude each other")
    if steps is not None and steps < 1:
        raise InputError(f"--steps must be >= 1, got {steps}")
    if minutes is not None and not minutes > 0:
        raise InputError(f"--minutes must be positive, got {minutes}")

    previous: ReferenceModel | None = None
    state: dict[str, Any] | None = None
    if resume:
        if not out.is_file():
            raise InputError(f"{out}: nothing to resume (no such model); drop --resume to start a new one")
        previous = load_reference_model(out)
        state = load_checkpoint_dict(state_path(out), STATE_KIND)
        config = _resume_config(previous, state, config)
    else:
        config = config or TrainConfig()
        if out.exists() and not overwrite:
            raise InputError(f"{out}: already exists; pass --resume to continue it, --overwrite to replace "
                             "it, or choose another --out")
    if steps is None and minutes is None:
        steps = config.steps

    track, frames, count = read_reference(poses_path, frames_path, align)
    usable = usable_frames(track, config.min_visible_joints)
    if not usable.any():
        raise InputError(f"{poses_path}: no frame has a usable pose (>= {config.min_visible_joints} of "
                         f"{len(track.joint_layout)} joints visible)")
    skipped = int((~usable).sum())
    if skipped:
        log.warning("%d of %d frames have no usable pose and are skipped", skipped, count)

    if previous is not None:
        canvas = previous.canvas
        if canvas.image_size != track.image_size:
            raise InputError(f"{frames_path}: frames are {track.image_size[0]}x{track.image_size[1]}, "
                             f"the model was trained on {canvas.image_size[0]}x{canvas.image_size[1]}")
        codes, codes_weights = previous.reference_codes, previous.codes_weights
        codes_path = previous.codes_weights_path
        stats = previous.scale_stats
    else:
        canvas = choose_canvas(track.joints[usable], track.image_size, config.size, config.canvas_mode,
                               config.canvas_margin)
        codes, codes_weights, codes_path = reference_codes(track, weights)
        stats = _maybe_scale_stats(track)

    torch.manual_seed(config.seed)
    generator = previous.build_generator(device).train() if previous is not None else None
    trainer = Trainer(config, device, generator)
    rng = torch.Generator().manual_seed(config.seed)
    if state is not None and previous is not None:
        trainer.load_state_dict(state["trainer"])
        rng.set_state(state["rng"])
        if trainer.step_count != int(previous.training.get("steps", trainer.step_count)):
            log.warning("%s and its state disagree on the step (%s vs %d); continuing from the state", out,
                        previous.training.get("steps"), trainer.step_count)
    summary = track_summary(track, usable)
    start_step = trainer.step_count
    t0 = time.perf_counter()  # restarted once the frames are read: --minutes counts training only
    seconds_before = float(previous.training.get("seconds", 0.0)) if previous is not None else 0.0
    interrupted = False
    losses: dict[str, float] = {}

    # Training needs autograd whatever mode the caller left torch in.
    with torch.enable_grad(), frame_store(count, canvas.size) as store:
        for i, frame in enumerate(frames):
            if i >= count:
                break
            store[i] = cut_frame(frame, canvas)
            if progress is not None:
                progress(TrainProgress("reading", i + 1, count, time.perf_counter() - t0, None, {}))
        data = ReferenceData(store, image_to_canvas(track.joints, canvas), usable, canvas.size)
        rows = _preview_rows(data.indices)
        log.info("read %d frames in %.1f s", count, time.perf_counter() - t0)
        t0 = time.perf_counter()

        def save() -> None:
            model = ReferenceModel(
                generator_name="unet",
                generator_config=trainer.g.config,
                generator_state=trainer.g.state_dict(),
                canvas=canvas,
                scale_stats=stats,
                reference_track=track,
                track_summary=summary,
                reference_codes=codes,
                codes_weights=codes_weights,
                codes_weights_path=codes_path,
                training={
                    "steps": trainer.step_count,
                    "seconds": seconds_before + time.perf_counter() - t0,
                    "config": config.to_dict(),
                    "device": str(device),
                },
                temporal=config.temporal,
            )
            payload = {"kind": STATE_KIND, "format_version": FORMAT_VERSION, "trainer": trainer.state_dict(),
                       "rng": rng.get_state(), "train_config": config.to_dict()}
            with atomic_file(state_path(out), overwrite=True) as tmp:
                torch.save(payload, tmp)
            save_reference_model(model, out, overwrite=True)

        last_save = time.perf_counter()
        limit_s = minutes * 60.0 if minutes is not None else None
        try:
            while (steps is None or trainer.step_count < steps) and (
                limit_s is None or time.perf_counter() - t0 < limit_s
            ):
                pick = torch.randint(len(data.indices), (config.batch_size,), generator=rng).numpy()
                sample = data.batch(data.indices[pick])
                sample = warp_batch(sample, random_affines(config.batch_size, canvas.size, config.augment, rng))
                sample = {k: v.to(device) for k, v in sample.items()}
                losses = trainer.train_step(sample, *trainer.previous_input(sample, rng))
                if trainer.step_count % config.preview_every == 0:
                    write_png(preview_grid(trainer, data, rows), preview_path(out))
                if time.perf_counter() - last_save > config.save_every_s:
                    save()
                    last_save = time.perf_counter()
                if progress is not None:
                    elapsed = time.perf_counter() - t0
                    progress(TrainProgress("training", trainer.step_count, steps, elapsed, limit_s, losses))
        except KeyboardInterrupt:
            interrupted = True
            log.warning("interrupted at step %d; saving", trainer.step_count)
        write_png(preview_grid(trainer, data, rows), preview_path(out))
        save()

    return TrainResult(
        model_path=out, preview_path=preview_path(out), steps=trainer.step_count,
        steps_this_run=trainer.step_count - start_step, seconds=time.perf_counter() - t0, frames=count,
        usable_frames=int(usable.sum()), skipped_frames=skipped, has_codes=codes is not None,
        interrupted=interrupted, last_losses=losses,
    )


def _maybe_scale_stats(track: PoseTrack) -> ScaleStats | None:
    try:
        return scale_stats(track.joints, track.joint_layout)
    except InputError as exc:
        log.warning("reference: %s; --method global-scale will not be available", exc)
        return None


def _resume_config(previous: ReferenceModel, state: dict[str, Any], given: TrainConfig | None) -> TrainConfig:
    """The stored run's config; of ``given`` only batch size, preview and save intervals apply."""
    stored = state.get("train_config") or previous.training.get("config")
    if not isinstance(stored, dict):
        raise InputError("model state has no training config; cannot resume")
    aug = AugmentConfig(**stored.pop("augment"))
    loss = LossConfig(**stored.pop("loss"))
    config = TrainConfig(**stored, augment=aug, loss=loss)
    if given is None:
        return config
    if given.size != config.size:
        raise InputError(f"--size {given.size} differs from the model's {config.size}; cannot resume at another size")
    return replace(config, batch_size=given.batch_size, preview_every=given.preview_every,
                   save_every_s=given.save_every_s)
