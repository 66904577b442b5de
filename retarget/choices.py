"""Closed sets of names the retargeting code accepts, as enums (no torch here: the command line lists them)."""

from __future__ import annotations

from enum import Enum


class Variant(str, Enum):
    """Network variants (:data:`retarget.network.model.VARIANTS`): the paper's three-encoder model and the authors'
    two-encoder models."""

    FULL = "full"
    SKELETON = "skeleton"
    VIEW = "view"


class Ablation(str, Enum):
    """Ablations of the paper's objective (:data:`retarget.training.losses.ABLATIONS`)."""

    FULL = "full"
    NO_TRIPLET = "no-triplet"
    RECON_TRIPLET = "recon-triplet"


class Split(str, Enum):
    """The held-out splits of the motion world an evaluation may run on."""

    TEST = "test"
    VAL = "val"
