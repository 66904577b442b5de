"""The Trainer: generator, discriminator, their losses and optimisers, and one training step.

G trains on ``(pose map t, previous frame)`` -> frame t with L1 to the real frame, least-squares GAN and
pix2pixHD's feature matching on D's activations; D judges the consecutive pair
``(pose t-1, pose t, frame t-1, frame t)``, real frames against G's. Images are ``[B, 3, S, S]`` in [-1, 1].
"""

from __future__ import annotations

from typing import Any

import torch
import torch.nn.functional as F
from torch import Tensor

from clone.networks import (
    PatchDiscriminator,
    UNetGenerator,
    build_discriminator,
    build_generator,
    discriminator_input,
    feature_matching_loss,
    generator_input,
    lsgan_loss,
)
from clone.train_ref.augment import degrade_previous
from clone.train_ref.config import TrainConfig


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
        """What resuming needs besides G's weights: D, both optimisers and the step."""
        return {
            "discriminator": {"name": "patch", "config": self.d.config.to_dict(), "state_dict": self.d.state_dict()},
            "opt_g": self.opt_g.state_dict(),
            "opt_d": self.opt_d.state_dict(),
            "step": self.step_count,
        }

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore what :meth:`state_dict` returned (G's weights are restored by building G from them)."""
        self.d.load_state_dict(state["discriminator"]["state_dict"])
        self.opt_g.load_state_dict(state["opt_g"])
        self.opt_d.load_state_dict(state["opt_d"])
        self.step_count = int(state["step"])
