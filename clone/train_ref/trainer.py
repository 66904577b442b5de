"""The Trainer: generator, discriminator, their losses and optimisers, and one training step.

G trains on ``(pose map t, previous frame)`` -> frame t with L1 to the real frame, least-squares GAN and
pix2pixHD's feature matching on D's activations; D judges the consecutive pair
``(pose t-1, pose t, frame t-1, frame t)``, real frames against G's. Images are ``[B, 3, S, S]`` in [-1, 1].
A generator trained with a background plate gets the sample's (warped) ``plate`` and composites over it, so
every loss sees the composite.

Under ``torchrun`` (:mod:`retarget.training.distributed`) both networks train in DistributedDataParallel: each process
steps on its part of the global batch, and the random numbers of the whole batch are drawn on every process
(:meth:`Trainer.previous_input`), so the step is that of one process. On CUDA the networks run in bfloat16
autocast when ``dtype`` says so.
"""

from __future__ import annotations

from typing import Any

import torch
import torch.nn.functional as F
from torch import Tensor

from clone.model.face import (
    FACE_PASS_RADII,
    blend_mask,
    build_face_pass,
    face_boxes,
    face_crops,
    paste,
    refine_crops,
)
from clone.model.networks import (
    FRAME_CHANNELS,
    POSE_CHANNELS,
    DiscriminatorConfig,
    PatchDiscriminator,
    UNetGenerator,
    build_discriminator,
    build_generator,
    discriminator_input,
    feature_matching_loss,
    generator_input,
    lsgan_loss,
)
from clone.train_ref import losses
from clone.train_ref.augment import degrade_previous
from clone.train_ref.config import TrainConfig
from retarget.training import distributed


class Trainer:
    """Generator, discriminator, optimisers and one training step.

    Args:
        config: the run's settings.
        device: where the networks live (this process's GPU under ``torchrun``).
        generator: an existing generator (resuming); a fresh one when None.
        dtype: autocast dtype of the networks (bfloat16 on CUDA), None for float32.
        face_pass: an existing face pass (resuming, or a model started from); a fresh one when None and the
            config asks for one.
    """

    def __init__(
        self, config: TrainConfig, device: torch.device, generator: UNetGenerator | None = None,
        dtype: torch.dtype | None = None, face_pass: UNetGenerator | None = None,
    ) -> None:
        self.config = config
        self.device = device
        self.dtype = dtype
        self.g = (generator or build_generator("unet", config.generator_config())).to(device).train()
        self.d: PatchDiscriminator = build_discriminator("patch", config.discriminator_config()).to(device).train()
        # The training step calls these (DistributedDataParallel with several processes); everything else,
        # previews and checkpoints, the plain networks.
        self._g_step = distributed.wrap(self.g, device)
        self._d_step = distributed.wrap(self.d, device)
        betas = (config.beta1, 0.999)
        self.opt_g = torch.optim.Adam(self.g.parameters(), lr=config.lr, betas=betas)
        self.opt_d = torch.optim.Adam(self.d.parameters(), lr=config.lr, betas=betas)
        # Training only: a PatchGAN on face crops (pose map + frame), as Everybody Dance Now's face GAN judges
        # the face; the generator that drives is unchanged.
        self.face_d: PatchDiscriminator | None = None
        if config.loss.face_gan:
            face_config = DiscriminatorConfig(in_channels=POSE_CHANNELS + FRAME_CHANNELS,
                                              base_channels=config.disc_channels, num_layers=2)
            self.face_d = build_discriminator("patch", face_config).to(device).train()
            self._face_d_step = distributed.wrap(self.face_d, device)
            self.opt_face_d = torch.optim.Adam(self.face_d.parameters(), lr=config.lr, betas=betas)
        # The face pass (clone.model.face): its U-Net and its own discriminator on face crops, trained on G's
        # frames without a gradient into G.
        self.face_pass: UNetGenerator | None = None
        if config.face_pass:
            self.face_pass = (face_pass or build_face_pass()).to(device).train()
            pass_config = DiscriminatorConfig(in_channels=POSE_CHANNELS + FRAME_CHANNELS,
                                              base_channels=config.disc_channels, num_layers=2)
            self.face_pass_d: PatchDiscriminator = build_discriminator("patch", pass_config).to(device).train()
            self._face_pass_step = distributed.wrap(self.face_pass, device)
            self._face_pass_d_step = distributed.wrap(self.face_pass_d, device)
            self.opt_face_pass = torch.optim.Adam(self.face_pass.parameters(), lr=config.lr, betas=betas)
            self.opt_face_pass_d = torch.optim.Adam(self.face_pass_d.parameters(), lr=config.lr, betas=betas)
        self.step_count = 0

    def _optimisers(self) -> list[torch.optim.Optimizer]:
        optimisers = [self.opt_g, self.opt_d]
        if self.face_d is not None:
            optimisers.append(self.opt_face_d)
        if self.face_pass is not None:
            optimisers += [self.opt_face_pass, self.opt_face_pass_d]
        return optimisers

    def set_lr(self, factor: float) -> None:
        """Every optimiser's learning rate to ``factor`` times the config's."""
        for optimiser in self._optimisers():
            for group in optimiser.param_groups:
                group["lr"] = self.config.lr * factor

    def generate(self, pose: Tensor, prev: Tensor, plate: Tensor | None = None, exemplar: Tensor | None = None
                 ) -> Tensor:
        """G's frame (float32) for [B, 3, S, S] pose maps, previous frames, background plates (or None) and
        exemplars (or None)."""
        with distributed.autocast(self.device, self.dtype):
            return self.g(self.g_input(pose, prev, exemplar), plate).float()

    def g_input(self, pose: Tensor, prev: Tensor, exemplar: Tensor | None) -> Tensor:
        """What G reads (:func:`clone.model.networks.generator_input`): the previous frame only when temporal,
        the exemplar only when it sees one."""
        return generator_input(pose, prev if self.config.temporal else None,
                               exemplar if self.config.exemplar else None)

    def refine_faces(self, frame: Tensor, pose: Tensor, face: Tensor) -> Tensor:
        """G's frames [B, 3, S, S] with the face pass applied where ``face`` [B, 1, S, S] (the samples' face
        discs) shows one, as `clone drive` applies it; the frames as they are without a face pass."""
        if self.face_pass is None:
            return frame
        boxes, present = face_boxes(face, FACE_PASS_RADII)
        crop = face_crops(frame, boxes)
        with distributed.autocast(self.device, self.dtype):
            refined = refine_crops(self.face_pass, face_crops(pose, boxes), crop, blend_mask(frame.device)).float()
        return paste(frame, (refined - crop) * present[:, None, None, None].float(), boxes)

    def previous_input(
        self, sample: dict[str, Tensor], generator: torch.Generator, part: slice | None = None,
        total: int | None = None,
    ) -> tuple[Tensor, Tensor]:
        """What G gets as the previous frame, and the previous frame D sees in a fake pair.

        ``prev_source == "real"``: the real previous frame, degraded; D's fake pair starts from the real one.
        ``prev_source == "generated"``: G's own frame for ``t-1`` made from zeros (no gradient), degraded, as
        in Everybody Dance Now; D's fake pair is then entirely generated.

        Args:
            sample: the batch, or this process's ``part`` of a global batch of ``total`` samples.
            generator: the run's CPU generator (in the same state on every process).
            part: where ``sample`` sits in the global batch (default: it is the whole batch).
            total: samples in the global batch.

        Returns:
            ``(G's previous-frame input, D's previous frame)``, both [B, 3, S, S].
        """
        cfg = self.config
        if cfg.prev_source == "generated":
            with torch.no_grad():
                prev = self.generate(sample["pose_prev"], torch.zeros_like(sample["frame_prev"]), sample.get("plate"),
                                     sample.get("exemplar_prev"))
        else:
            prev = sample["frame_prev"]
        has_prev = sample["has_prev"]
        prev = torch.where(has_prev[:, None, None, None], prev, 0.0)
        if part is None or total is None or (part.start, part.stop) == (0, total):
            return degrade_previous(prev, has_prev, cfg.augment, cfg.prev_dropout, generator), prev
        # The degradation draws its numbers for the whole batch: put this part in a batch of zeros so that it
        # gets those a single process gives it, and the generator ends alike on every process.
        full = prev.new_zeros((total, *prev.shape[1:]))  # [total, 3, S, S]
        full[part] = prev
        full_has = has_prev.new_zeros(total)
        full_has[part] = has_prev
        return degrade_previous(full, full_has, cfg.augment, cfg.prev_dropout, generator)[part], prev

    def train_step(self, sample: dict[str, Tensor], prev_input: Tensor, fake_prev: Tensor | None = None,
                   weight: float = 1.0) -> dict[str, float]:
        """One update of G and then of D.

        Args:
            sample: the (augmented) batch of :meth:`ReferenceData.batch`, on the device.
            prev_input: [B, 3, S, S] what G gets as the previous frame.
            fake_prev: [B, 3, S, S] previous frame of D's fake pairs (default: the real one).
            weight: factor of this process's mean losses (:func:`retarget.training.distributed.shard_weight`).

        Returns:
            Loss values (means over ``sample``).
        """
        w = self.config.loss
        real = sample["frame_cur"]
        pair = (sample["pose_prev"], sample["pose_cur"], sample["frame_prev"])
        real_in = discriminator_input(*pair, real)  # [B, 12, S, S]
        fake_pair = (sample["pose_prev"], sample["pose_cur"], sample["frame_prev"] if fake_prev is None else fake_prev)

        with distributed.autocast(self.device, self.dtype):
            g_in = self.g_input(sample["pose_cur"], prev_input, sample.get("exemplar_cur"))
            fake = self._g_step(g_in, sample.get("plate")).float()  # [B, 3, S, S]
            # The plain D: its parameters get no gradient here, which DistributedDataParallel would wait for.
            self.d.requires_grad_(False)
            fake_feats = self.d(discriminator_input(*fake_pair, fake))
            with torch.no_grad():
                real_feats = self.d(real_in)
            gan = lsgan_loss(fake_feats[-1].float(), True)
            fm = feature_matching_loss([f.float() for f in fake_feats], [f.float() for f in real_feats])
        # The reconstruction terms in float32: SSIM's variances and the pyramid's fine bands are small differences.
        if w.person or w.face or w.ssim or w.laplacian:
            weights = losses.person_weights(real, sample.get("plate"), sample["pose_cur"], w.person,
                                            sample.get("face"), w.face)
            l1 = losses.weighted_l1(fake, real, weights)
        else:
            weights, l1 = None, F.l1_loss(fake, real)
        loss_g = w.l1 * l1 + w.gan * gan + w.feature_matching * fm
        terms = {}
        face = None
        if self.face_d is not None and "face" in sample:
            boxes, present = face_boxes(sample["face"], losses.FACE_CROP_RADII)
            share = present.float() / present.float().sum().clamp(min=1.0)  # [B] mean over samples with a face
            pose_crop = face_crops(sample["pose_cur"], boxes)
            real_face = torch.cat([pose_crop, face_crops(real, boxes)], dim=1)  # [B, 6, 64, 64]
            fake_face = torch.cat([pose_crop, face_crops(fake, boxes)], dim=1)
            face = (real_face, fake_face, share)
            self.face_d.requires_grad_(False)
            fake_feats_face = self.face_d(fake_face)
            with torch.no_grad():
                real_feats_face = self.face_d(real_face)
            per_sample = ((fake_feats_face[-1] - 1.0) ** 2).mean(dim=(1, 2, 3))  # [B]
            fm_face = torch.stack([(f - r.detach()).abs().mean(dim=(1, 2, 3))
                                   for f, r in zip(fake_feats_face[:-1], real_feats_face[:-1])]).mean(dim=0)
            terms["face_gan"] = (share * per_sample).sum()
            loss_g = loss_g + w.face_gan * (terms["face_gan"] + w.feature_matching * (share * fm_face).sum())
        if w.ssim:
            terms["ssim"] = losses.ssim_loss(fake, real, weights)
            loss_g = loss_g + w.ssim * terms["ssim"]
        if w.laplacian:
            terms["laplacian"] = losses.laplacian_loss(fake, real, weights)
            loss_g = loss_g + w.laplacian * terms["laplacian"]
        self.opt_g.zero_grad(set_to_none=True)
        (loss_g if weight == 1.0 else weight * loss_g).backward()
        self.opt_g.step()

        self.d.requires_grad_(True)
        with distributed.autocast(self.device, self.dtype):
            d_real = self._d_step(real_in)[-1].float()
            d_fake = self._d_step(discriminator_input(*fake_pair, fake.detach()))[-1].float()
            loss_d = 0.5 * (lsgan_loss(d_real, True) + lsgan_loss(d_fake, False))
        self.opt_d.zero_grad(set_to_none=True)
        (loss_d if weight == 1.0 else weight * loss_d).backward()
        self.opt_d.step()
        if face is not None:
            real_face, fake_face, share = face
            self.face_d.requires_grad_(True)
            d_real = ((self._face_d_step(real_face)[-1] - 1.0) ** 2).mean(dim=(1, 2, 3))
            d_fake = (self._face_d_step(fake_face.detach())[-1] ** 2).mean(dim=(1, 2, 3))
            loss_face_d = 0.5 * (share * (d_real + d_fake)).sum()
            self.opt_face_d.zero_grad(set_to_none=True)
            (loss_face_d if weight == 1.0 else weight * loss_face_d).backward()
            self.opt_face_d.step()
            terms["face_d"] = loss_face_d
        if self.face_pass is not None and "face" in sample:
            terms.update(self.face_pass_step(sample, fake.detach(), weight))
        self.step_count += 1
        return {"l1": l1.item(), "gan": gan.item(), "fm": fm.item(), "d": loss_d.item(),
                **{k: v.item() for k, v in terms.items()}}

    def face_pass_step(self, sample: dict[str, Tensor], fake: Tensor, weight: float = 1.0) -> dict[str, Tensor]:
        """One update of the face pass and then of its discriminator, on G's frames ``fake`` [B, 3, S, S]
        (no gradient into G): L1 to the real crop inside the blend mask, least-squares GAN and feature
        matching at the run's weights. Samples without a face count zero (their step still runs, so that
        every process of a group steps alike)."""
        w = self.config.loss
        boxes, present = face_boxes(sample["face"], FACE_PASS_RADII)
        share = present.float() / present.float().sum().clamp(min=1.0)  # [B] mean over samples with a face
        mask = blend_mask(fake.device)  # [1, 1, C, C]
        pose_crop = face_crops(sample["pose_cur"], boxes)  # [B, 3, C, C]
        real_crop = face_crops(sample["frame_cur"], boxes)
        with distributed.autocast(self.device, self.dtype):
            refined = refine_crops(self._face_pass_step, pose_crop, face_crops(fake, boxes), mask).float()
            self.face_pass_d.requires_grad_(False)
            fake_feats = self.face_pass_d(torch.cat([pose_crop, refined], dim=1))
            with torch.no_grad():
                real_feats = self.face_pass_d(torch.cat([pose_crop, real_crop], dim=1))
        l1 = (mask * (refined - real_crop).abs()).mean(dim=(1, 2, 3)) / mask.mean()  # [B]
        gan = ((fake_feats[-1].float() - 1.0) ** 2).mean(dim=(1, 2, 3))
        fm = torch.stack([(f.float() - r.float()).abs().mean(dim=(1, 2, 3))
                          for f, r in zip(fake_feats[:-1], real_feats[:-1])]).mean(dim=0)
        loss = (share * (w.l1 * l1 + w.gan * gan + w.feature_matching * fm)).sum()
        self.opt_face_pass.zero_grad(set_to_none=True)
        (loss if weight == 1.0 else weight * loss).backward()
        self.opt_face_pass.step()

        self.face_pass_d.requires_grad_(True)
        with distributed.autocast(self.device, self.dtype):
            d_real = ((self._face_pass_d_step(torch.cat([pose_crop, real_crop], dim=1))[-1].float() - 1.0) ** 2)
            d_fake = self._face_pass_d_step(torch.cat([pose_crop, refined.detach()], dim=1))[-1].float() ** 2
            loss_d = 0.5 * (share * (d_real.mean(dim=(1, 2, 3)) + d_fake.mean(dim=(1, 2, 3)))).sum()
        self.opt_face_pass_d.zero_grad(set_to_none=True)
        (loss_d if weight == 1.0 else weight * loss_d).backward()
        self.opt_face_pass_d.step()
        return {"face_pass_l1": (share * l1).sum().detach(), "face_pass_gan": (share * gan).sum().detach(),
                "face_pass_d": loss_d.detach()}

    def state_dict(self) -> dict[str, Any]:
        """What resuming needs besides G's weights (and the face pass's, stored as the model's ``face_pass``): D,
        the face D and the face pass's D when there are, every optimiser and the step."""
        state = {
            "discriminator": {"name": "patch", "config": self.d.config.to_dict(), "state_dict": self.d.state_dict()},
            "opt_g": self.opt_g.state_dict(),
            "opt_d": self.opt_d.state_dict(),
            "step": self.step_count,
        }
        if self.face_d is not None:
            state["face_discriminator"] = {"config": self.face_d.config.to_dict(),
                                           "state_dict": self.face_d.state_dict(),
                                           "optimizer": self.opt_face_d.state_dict()}
        if self.face_pass is not None:
            state["face_pass"] = {"optimizer": self.opt_face_pass.state_dict(),
                                  "discriminator": {"config": self.face_pass_d.config.to_dict(),
                                                    "state_dict": self.face_pass_d.state_dict(),
                                                    "optimizer": self.opt_face_pass_d.state_dict()}}
        return state

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore what :meth:`state_dict` returned (G's weights are restored by building G from them)."""
        self.d.load_state_dict(state["discriminator"]["state_dict"])
        if self.face_d is not None and "face_discriminator" in state:
            self.face_d.load_state_dict(state["face_discriminator"]["state_dict"])
            self.opt_face_d.load_state_dict(state["face_discriminator"]["optimizer"])
        if self.face_pass is not None and "face_pass" in state:
            self.opt_face_pass.load_state_dict(state["face_pass"]["optimizer"])
            self.face_pass_d.load_state_dict(state["face_pass"]["discriminator"]["state_dict"])
            self.opt_face_pass_d.load_state_dict(state["face_pass"]["discriminator"]["optimizer"])
        self.opt_g.load_state_dict(state["opt_g"])
        self.opt_d.load_state_dict(state["opt_d"])
        self.step_count = int(state["step"])
