"""The training objective of Aberman et al. 2019.

For two triples (m1, c1, v1), (m2, c2, v2) the network encodes both, decodes all combinations of their
motion, skeleton and view codes and compares each with the ground-truth window of that combination
(reconstruction for the two originals, cross reconstruction for the other six). A triplet loss pulls
the codes of windows sharing a motion (skeleton, view) together and pushes the other triple's away, and
a foot-velocity loss matches the global velocity of the ankles. Beyond the paper, a trajectory loss
compares the root path integrated over the window (up to one translation), which the per-frame velocity
error lets drift.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from pose_io.measures import ANKLES
from retarget.choices import Ablation
from retarget.network.model import RetargetNet
from retarget.network.preprocess import (
    LAYOUT,
    NormStats,
    channels_to_joints,
    pose_channels,
    velocity_channels,
)
from retarget.training.augment import COMBOS, MOTION, SKELETON, VIEW, combo_index
from retarget.training.code_losses import (
    anchor_codes,
    combo_skeleton_codes,
    skeleton_cluster_loss,
    skeleton_proportion_loss,
    skeleton_ratio_loss,
    triplet_loss,
)


@dataclass(frozen=True)
class LossConfig:
    """Terms and weights of the objective (defaults: the paper's).

    Attributes:
        cross: decode the cross combinations (False: plain reconstruction of the two inputs).
        triplet: add the triplet loss on motion and static codes.
        triplet_margin: its margin.
        triplet_weight: its weight.
        foot_weight: weight of the foot-velocity loss (0 = off).
        trajectory_weight: weight of the integrated root-trajectory loss (0 = off; not in the paper).
        spread_weight: weight of the range-of-motion loss (0 = off; not in the paper): the spread over time
            of every output channel should match the truth's. Where a 2D input leaves the motion ambiguous,
            the squared error alone is smallest for an average of the candidates, a damped motion.
        cycle_weight: weight of the cycle term on unlabelled windows (0 = off; not in the paper): a window's
            motion moved onto another window's skeleton and view, encoded again and moved back onto its own,
            should give the window back. Real tracks have no ground truth for a cross combination, so this is
            what checks that retargeting them keeps the motion (a damped copy cannot be undone).
        skeleton_ratio_weight: weight of the skeleton-ratio term (0 = off; not in the paper): a window's skeleton
            code should lie nearer the code of another window of its character (other motion, other view) than
            ``skeleton_ratio`` times its distance to the code of another character in the same motion and view.
            A ratio, so shrinking or growing the codes cannot satisfy it, unlike the triplet's fixed margin;
            it asks the skeleton encoder to see past the view.
        skeleton_ratio: that ratio.
        skeleton_cluster_weight: weight of the skeleton-cluster term (0 = off; not in the paper; needs the
            samples' ids): a character's skeleton codes over the 2 motions x 2 views of its sample should spread
            (mean distance to their centre) less than ``skeleton_cluster_ratio`` times the distance from that
            centre to the nearest other character's in the batch: the silhouette the paper reports, on the
            hardest negatives a batch holds.
        skeleton_cluster_ratio: that ratio.
        skeleton_proportion_weight: weight of the skeleton-proportion term (0 = off; not in the paper; needs the
            samples' ids and the training characters' proportions): the distances between the batch's skeleton
            codes should follow the distances between their characters' proportions (standardised log bone
            lengths over height), each divided by its mean: codes of one character together, codes of two
            characters as far apart as their bodies differ.
    """

    cross: bool = True
    triplet: bool = True
    triplet_margin: float = 0.3
    triplet_weight: float = 0.1
    foot_weight: float = 0.5
    trajectory_weight: float = 0.0
    spread_weight: float = 0.0
    cycle_weight: float = 0.0
    skeleton_ratio_weight: float = 0.0
    skeleton_ratio: float = 0.5
    skeleton_cluster_weight: float = 0.0
    skeleton_cluster_ratio: float = 0.5
    skeleton_proportion_weight: float = 0.0



# Ablations of the paper's objective, by plain name; an Ablation looks up the same entry.
ABLATIONS: dict[str, LossConfig] = {
    Ablation.FULL.value: LossConfig(),
    Ablation.NO_TRIPLET.value: LossConfig(triplet=False),
    Ablation.RECON_TRIPLET.value: LossConfig(cross=False),
}


def ablation_config(name: str) -> LossConfig:
    """Loss settings of a named ablation; an unknown name raises ValueError listing the valid ones."""
    try:
        return ABLATIONS[name]
    except KeyError:
        raise ValueError(f"unknown ablation {name!r}; valid: {', '.join(ABLATIONS)}") from None


def foot_velocity(x: torch.Tensor, stats: NormStats, min_scale: float = 1.0) -> torch.Tensor:
    """Global ankle velocity in units of the root-velocity std: [B, 30, T] -> [B, T-1, 2, 2].

    Those are the units of the velocity channels, so the term weighs like the reconstruction; the std
    is floored at ``min_scale`` canvas pixels per frame for data whose root hardly moves.
    """
    joints = channels_to_joints(x, stats)[:, :, LAYOUT.indices(ANKLES)]  # [B, T, 2, 2]
    scale = torch.tensor(np.maximum(stats.velocity_std, min_scale), dtype=x.dtype, device=x.device)
    return (joints[:, 1:] - joints[:, :-1]) / scale


def trajectory_error(out: torch.Tensor, truth: torch.Tensor) -> torch.Tensor:
    """Squared error of the integrated root path, one translation removed: [B, 30, T] x2 -> [B].

    The velocity channels are in units of the root-velocity std; their running sum is the root path in
    those units. The mean over the window is subtracted (the path may be placed anywhere) and the result
    is divided by ``T`` so that windows of any length weigh alike.
    """
    drift = torch.cumsum(velocity_channels(out) - velocity_channels(truth), dim=-1)  # [B, 2, T]
    drift = drift - drift.mean(dim=-1, keepdim=True)
    return (drift**2).mean(dim=(1, 2)) / out.shape[-1]


def spread_error(out: torch.Tensor, truth: torch.Tensor) -> torch.Tensor:
    """Squared difference of the temporal spread (std over time) of every pose channel: [B, 30, T] x2 -> [B]."""
    return ((pose_channels(out).std(dim=-1) - pose_channels(truth).std(dim=-1)) ** 2).mean(dim=1)


def used_combos(model: RetargetNet, cross: bool) -> list[int]:
    """Combinations a model is trained on.

    A code the model lacks is shared by both triples of its samples, so only combinations that take it
    from the motion's triple are distinct; without ``cross`` only the two original triples remain.
    """
    has = {SKELETON: model.body_encoder is not None, VIEW: model.view_encoder is not None}
    combos = [0, combo_index(1, 1, 1)]
    if cross:
        combos = [
            k for k, c in enumerate(COMBOS) if all(has[f] or c[f] == c[MOTION] for f in (SKELETON, VIEW))
        ]
    return combos


def _codes(model: RetargetNet, x: torch.Tensor) -> dict[int, torch.Tensor]:
    codes = {MOTION: model.encode_motion(x)}
    if model.body_encoder is not None:
        codes[SKELETON] = model.encode_body(x)
    if model.view_encoder is not None:
        codes[VIEW] = model.encode_view(x)
    return codes


def objective(
    model: RetargetNet, inputs: torch.Tensor, targets: torch.Tensor, stats: NormStats, config: LossConfig,
    ids: torch.Tensor | None = None, proportions: torch.Tensor | None = None,
) -> dict[str, torch.Tensor]:
    """Losses of one batch of 8-combination samples.

    Args:
        model: the network (train or eval mode).
        inputs: [B, 8, 30, T] normalised network inputs (corrupted), combination order :data:`COMBOS`.
        targets: [B, 8, 30, T] normalised ground truth.
        stats: normalisation statistics (for the foot velocity).
        config: loss terms and weights.
        ids: [B, 2, 3] (motion, character, view) ids of the two triples (for the skeleton-cluster term).
        proportions: [C, P] the characters' standardised log proportions, indexed by ``ids`` (for the
            skeleton-proportion term; without them the term is left out, as in validation on other characters).

    Returns:
        Named loss terms (already weighted) and their sum under ``"total"``.
    """
    b = inputs.shape[0]
    first, second = 0, combo_index(1, 1, 1)
    both = _codes(model, torch.cat([inputs[:, first], inputs[:, second]]))  # each [2B, C, ...]
    triple = {f: code.reshape(2, b, *code.shape[1:]) for f, code in both.items()}  # [2, B, C, ...]

    combos = used_combos(model, config.cross)
    def pick(factor: int) -> torch.Tensor | None:
        if factor not in triple:
            return None
        index = torch.tensor([COMBOS[k][factor] for k in combos], device=inputs.device)
        return triple[factor][index].flatten(0, 1)  # [K * B, C, ...]

    out = model.decode(pick(MOTION), pick(SKELETON), pick(VIEW)).reshape(len(combos), b, *targets.shape[2:])
    truth = targets[:, combos].transpose(0, 1)  # [K, B, 30, T]
    per_combo = ((out - truth) ** 2).mean(dim=(1, 2, 3))  # [K]
    own = torch.tensor([k in (first, second) for k in combos], device=inputs.device)
    losses = {"rec": per_combo[own].sum()}
    if config.cross:
        losses["cross"] = per_combo[~own].sum()
    if config.foot_weight > 0:
        flat_out, flat_truth = out.flatten(0, 1), truth.flatten(0, 1)
        foot = ((foot_velocity(flat_out, stats) - foot_velocity(flat_truth, stats)) ** 2)
        losses["foot"] = config.foot_weight * foot.reshape(len(combos), -1).mean(dim=1).sum()
    if config.trajectory_weight > 0:
        path = trajectory_error(out.flatten(0, 1), truth.flatten(0, 1)).reshape(len(combos), -1)
        losses["trajectory"] = config.trajectory_weight * path.mean(dim=1).sum()
    if config.spread_weight > 0:
        spread = spread_error(out.flatten(0, 1), truth.flatten(0, 1)).reshape(len(combos), -1)
        losses["spread"] = config.spread_weight * spread.mean(dim=1).sum()
    ratio = config.skeleton_ratio_weight > 0 and SKELETON in triple
    # anchor codes of the factors a term needs, each encoded once
    needed = list(triple) if config.triplet else [SKELETON] if ratio else []
    anchors = {factor: anchor_codes(model, inputs, factor) for factor in needed}
    if config.triplet:
        losses["triplet"] = config.triplet_weight * triplet_loss(anchors, triple, config.triplet_margin)
    if ratio:
        losses["skeleton_ratio"] = config.skeleton_ratio_weight * skeleton_ratio_loss(
            anchors[SKELETON], triple[SKELETON], config.skeleton_ratio
        )
    if config.skeleton_cluster_weight > 0 and SKELETON in triple and ids is not None:
        codes = combo_skeleton_codes(model, inputs, triple[SKELETON], anchors.get(SKELETON))  # 8 x [B, D]
        own = [[combo_index(m, t, v) for m in (0, 1) for v in (0, 1)] for t in (0, 1)]  # character t's windows
        per_character = torch.stack([torch.stack([codes[k] for k in ks], dim=1) for ks in own], dim=1)  # [B, 2, 4, D]
        losses["skeleton_cluster"] = config.skeleton_cluster_weight * skeleton_cluster_loss(
            per_character, ids[:, :, SKELETON], config.skeleton_cluster_ratio
        )
    if config.skeleton_proportion_weight > 0 and SKELETON in triple and ids is not None and proportions is not None:
        codes = triple[SKELETON].flatten(2).flatten(0, 1)  # [2B, D]: triple 0's, then triple 1's
        characters = ids[:, :, SKELETON].transpose(0, 1).flatten()  # [2B] in the same order
        losses["skeleton_proportion"] = config.skeleton_proportion_weight * skeleton_proportion_loss(
            codes, proportions[characters]
        )
    losses["total"] = sum(losses.values())
    return losses


def self_reconstruction(
    model: RetargetNet, inputs: torch.Tensor, targets: torch.Tensor, stats: NormStats, config: LossConfig
) -> dict[str, torch.Tensor]:
    """Losses of unlabelled windows (real tracks): reconstruction from their own codes.

    Args:
        model: the network.
        inputs: [B, 30, T] corrupted inputs.
        targets: [B, 30, T] clean windows.
        stats: normalisation statistics.
        config: loss weights (the foot term is used).
    """
    out = model(inputs)
    losses = {"rec": ((out - targets) ** 2).mean()}
    if config.foot_weight > 0:
        foot = (foot_velocity(out, stats) - foot_velocity(targets, stats)) ** 2
        losses["foot"] = config.foot_weight * foot.mean()
    if config.trajectory_weight > 0:
        losses["trajectory"] = config.trajectory_weight * trajectory_error(out, targets).mean()
    if config.cycle_weight > 0 and len(inputs) > 1:
        losses["cycle"] = config.cycle_weight * ((cycle(model, inputs) - targets) ** 2).mean()
    losses["total"] = sum(losses.values())
    return losses


def cycle(model: RetargetNet, inputs: torch.Tensor) -> torch.Tensor:
    """Each window's motion moved onto the next window's static codes (batch order, cyclic) and back onto its own.

    Args:
        model: the network.
        inputs: [B, 30, T] normalised windows (B >= 2).

    Returns:
        [B, 30, T] the windows after the round trip.
    """
    def static(x: torch.Tensor) -> tuple[torch.Tensor | None, torch.Tensor | None]:
        body = model.encode_body(x) if model.body_encoder is not None else None
        view = model.encode_view(x) if model.view_encoder is not None else None
        return body, view

    moved = model.decode(model.encode_motion(inputs), *static(torch.roll(inputs, 1, dims=0)))
    return model.decode(model.encode_motion(moved), *static(inputs))
