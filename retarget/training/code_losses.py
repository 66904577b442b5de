"""The objective's terms on the static and motion codes: the paper's triplet loss, and beyond it the skeleton
codes' ratio, cluster and proportion terms (:func:`retarget.training.losses.objective` weighs and sums them).

Codes of the two triples are ``[2, B, D, ...]``; an anchor is the window that shares only one factor with a
triple (combination order :data:`retarget.training.augment.COMBOS`).
"""

from __future__ import annotations

import torch
import torch.nn.functional as F

from retarget.network.model import RetargetNet
from retarget.training.augment import COMBOS, MOTION, SKELETON, VIEW, combo_index


def skeleton_proportion_loss(codes: torch.Tensor, proportions: torch.Tensor) -> torch.Tensor:
    """Mean squared difference of the pairwise code distances and proportion distances, each over its mean.

    Args:
        codes: [N, D] skeleton codes.
        proportions: [N, P] their characters' proportions (standardised).
    """
    def distances(x: torch.Tensor) -> torch.Tensor:
        d = ((x[:, None] - x[None]) ** 2).sum(dim=-1).add(1e-8).sqrt()  # [N, N]; smooth at 0
        off = ~torch.eye(len(x), dtype=torch.bool, device=x.device)
        return d[off] / d[off].mean().clamp_min(1e-6)

    return ((distances(codes) - distances(proportions.to(codes.dtype))) ** 2).mean()


def combo_skeleton_codes(
    model: RetargetNet, inputs: torch.Tensor, triple: torch.Tensor, anchors: torch.Tensor | None
) -> list[torch.Tensor]:
    """Skeleton codes [B, D] of all 8 combinations, reusing the two triples' ([2, B, D, ...]) and the skeleton
    anchors' ([2B, D], :func:`anchor_codes`) where the objective already encoded them."""
    b = inputs.shape[0]
    known = {0: triple[0].flatten(1), combo_index(1, 1, 1): triple[1].flatten(1)}
    if anchors is not None:
        known[combo_index(1, 0, 1)], known[combo_index(0, 1, 0)] = anchors[:b], anchors[b:]
    rest = [k for k in range(len(COMBOS)) if k not in known]
    encoded = model.encode_body(inputs[:, rest].transpose(0, 1).flatten(0, 1)).flatten(1)  # [len(rest) * B, D]
    known.update(zip(rest, encoded.reshape(len(rest), b, -1)))
    return [known[k] for k in range(len(COMBOS))]


def skeleton_cluster_loss(codes: torch.Tensor, characters: torch.Tensor, ratio: float) -> torch.Tensor:
    """Mean of ``relu(spread / nearest - ratio)`` over the batch's characters: scale-free.

    Args:
        codes: [B, 2, K, D] skeleton codes of each sample's two characters, each in K windows.
        characters: [B, 2] their ids (a character twice in a batch is not its own negative).
        ratio: the spread asked for, in distances to the nearest other character.
    """
    flat = codes.flatten(0, 1)  # [2B, K, D]
    centre = flat.mean(dim=1)  # [2B, D]
    spread = (flat - centre[:, None]).norm(dim=-1).mean(dim=1)  # [2B]
    ids = characters.flatten()
    distance = torch.cdist(centre, centre).masked_fill(ids[:, None] == ids[None, :], float("inf"))  # [2B, 2B]
    nearest = distance.min(dim=1).values
    valid = torch.isfinite(nearest)
    if not valid.any():
        return codes.new_zeros(())
    return F.relu(spread[valid] / (nearest[valid] + 1e-6) - ratio).mean()


def triplet_loss(anchors: dict[int, torch.Tensor], triple: dict[int, torch.Tensor], margin: float) -> torch.Tensor:
    """For each code and each triple t: the code of the window sharing only that factor with triple t
    (anchor, :func:`anchor_codes`) should be nearer to triple t's code (positive) than to the other triple's
    (negative)."""
    total = next(iter(triple.values())).new_zeros(())
    for factor, codes in triple.items():
        anchor = anchors[factor]  # [2B, D]
        own = codes.flatten(2).flatten(0, 1)  # [2B, D]: triple 0's codes, then triple 1's
        other = codes.flip(0).flatten(2).flatten(0, 1)
        total = total + 2 * F.triplet_margin_loss(anchor, own, other, margin=margin)
    return total


def anchor_codes(model: RetargetNet, inputs: torch.Tensor, factor: int) -> torch.Tensor:
    """[2B, D] codes (of ``factor``) of the windows that share only ``factor`` with triple 0, then with triple 1."""
    anchors = []
    for t in (0, 1):
        combo = [1 - t] * 3
        combo[factor] = t
        anchors.append(inputs[:, combo_index(*combo)])
    encode = {MOTION: model.encode_motion, SKELETON: model.encode_body, VIEW: model.encode_view}[factor]
    return encode(torch.cat(anchors)).flatten(1)  # only this factor's encoder: the others' codes are not used


def skeleton_ratio_loss(anchor: torch.Tensor, codes: torch.Tensor, ratio: float) -> torch.Tensor:
    """Mean of ``relu(|a - own| / |a - other| - ratio)``: scale-free, 0 once each anchor is ``ratio`` times nearer
    its own triple's code than the other triple's.

    Args:
        anchor: [2B, D] codes of the windows sharing only this factor with triple 0, then triple 1.
        codes: [2, B, D, ...] the two triples' codes.
        ratio: the distance ratio asked for.
    """
    own = codes.flatten(2).flatten(0, 1)  # [2B, D]
    other = codes.flip(0).flatten(2).flatten(0, 1)
    near, far = (anchor - own).norm(dim=1), (anchor - other).norm(dim=1)
    return F.relu(near / (far + 1e-6) - ratio).mean()
