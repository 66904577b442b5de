"""The run's checkpoint: ONE reference-model file (:mod:`clone.model.reference`) with the generator and, under
``training``, everything a resumed run needs, written atomically together.

``training`` holds the run's record (``steps``, ``seconds``, ``device``, ``config``) and its resume state:
``trainer`` (:meth:`Trainer.state_dict`: discriminator, both optimisers, step, and the face pass's optimiser,
discriminator and its optimiser when the run trains one; the face pass's weights are the model's ``face_pass``) and ``rng`` (the state of the
run's CPU generator, which picks samples and draws the augmentation). Since nothing lives beside the model,
the state of one model cannot be resumed with the weights of another.

None of it depends on the number of processes that trained (``torchrun``, see :mod:`retarget.training.distributed`):
the networks and optimisers are the same on every process, and the generator, which draws the numbers of the
whole global batch on every process, is in the same state on all of them. Rank 0 writes the file; a model
resumes under any number of processes.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import torch

from clone.model.canvas import Canvas
from clone.model.exemplar import ExemplarBank
from clone.model.networks import FRAME_CHANNELS, _last_conv, build_generator
from clone.model.reference import ReferenceModel, load_reference_model, save_reference_model
from clone.train_ref.config import TrainConfig
from clone.train_ref.trainer import Trainer
from pose_io.errors import InputError
from pose_io.track import PoseTrack
from retarget.baselines.global_scale import ScaleStats

# The entries of ``training`` only resuming reads (the rest is the run's record: steps, seconds, device, config).
RESUME_STATE = ("trainer", "rng")
# Entries of ``training`` without which a model cannot be resumed.
RESUME_KEYS = ("config", *RESUME_STATE)


@dataclass(frozen=True)
class ReferenceInfo:
    """What the model file stores about the reference besides the generator; fixed for a run.

    Attributes:
        canvas: where the canvas sits in the reference's frames.
        scale_stats: feet range and heights for global scaling, or None.
        track: the reference's body15 track in its image pixels.
        summary: plain-data summary of the track (see :func:`clone.train_ref.data.track_summary`).
        codes: the retargeting network's codes of the reference, or None.
        codes_weights: SHA-256 of the weights that made ``codes``, or None.
        codes_weights_path: where those weights were, or None.
        plate: [S, S, 3] uint8 background plate on the canvas, or None (a run without one, or before the
            frames are read).
        details: the reference's track in the pose maps' layout (body31: with face, hands and feet), or None to
            draw ``track``.
        face_radius: the face's radius on the canvas (:func:`clone.model.face.face_radius`), or None (no face
            points, or before the frames are read): the face pass is stored only with it.
        prior: for a generator prior (:mod:`clone.train_ref.prior`), the synthetic performers it trains on
            (``PriorConfig`` as a dict, kept in the training record as ``prior``), else None.
        exemplars: the bank of the reference's frames its exemplars come from (:mod:`clone.model.exemplar`), or
            None (a generator that sees none, or a prior, which draws them anew from its performers).
    """

    canvas: Canvas
    scale_stats: ScaleStats | None
    track: PoseTrack
    summary: dict[str, Any]
    codes: dict[str, Any] | None
    codes_weights: str | None
    codes_weights_path: str | None
    plate: np.ndarray | None = None
    details: PoseTrack | None = None
    face_radius: float | None = None
    prior: dict[str, Any] | None = None
    exemplars: ExemplarBank | None = None


def checkpoint_model(
    trainer: Trainer, reference: ReferenceInfo, config: TrainConfig, rng: torch.Generator, seconds: float
) -> ReferenceModel:
    """The reference model of the run as it stands, with its training state.

    Args:
        trainer: the networks and optimisers.
        reference: what the file stores about the reference.
        config: the run's settings.
        rng: the run's CPU generator.
        seconds: training time so far, over all resumed runs.
    """
    training = {
        "steps": trainer.step_count,
        "seconds": seconds,
        "config": config.to_dict(),
        "device": str(trainer.device),
        "trainer": trainer.state_dict(),
        "rng": rng.get_state(),
    }
    if reference.prior is not None:
        training["prior"] = reference.prior
    face_pass = None
    if trainer.face_pass is not None and reference.face_radius is not None:
        face_pass = {"config": trainer.face_pass.config.to_dict(), "state_dict": trainer.face_pass.state_dict(),
                     "radius": reference.face_radius}
    return ReferenceModel(
        generator_name="unet",
        generator_config=trainer.g.config,
        generator_state=trainer.g.state_dict(),
        canvas=reference.canvas,
        scale_stats=reference.scale_stats,
        reference_track=reference.track,
        track_summary=reference.summary,
        reference_codes=reference.codes,
        codes_weights=reference.codes_weights,
        codes_weights_path=reference.codes_weights_path,
        training=training,
        temporal=config.temporal,
        plate=reference.plate,
        pose_layout=config.pose_layout,
        face_pass=face_pass,
        exemplars=reference.exemplars,
    )


def save_checkpoint(
    path: Path, trainer: Trainer, reference: ReferenceInfo, config: TrainConfig, rng: torch.Generator,
    seconds: float,
) -> None:
    """Write the run's model file with its training state atomically (see :func:`checkpoint_model`)."""
    save_reference_model(checkpoint_model(trainer, reference, config, rng, seconds), path, overwrite=True)


def load_resumable(path: str | os.PathLike) -> ReferenceModel:
    """The model at ``path``, checked to hold training state.

    Raises:
        InputError: no such file, not a readable model, or a model without training state.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: nothing to resume (no such model); drop --resume to start a new one")
    model = load_reference_model(path)
    training = model.training or {}
    if any(key not in training for key in RESUME_KEYS):
        raise InputError(f"{path}: holds no training state to resume (a stripped or pre-format-2 model); "
                         "pass --overwrite instead of --resume to train it anew")
    return model


def resume_config(model: ReferenceModel, given: TrainConfig | None, path: str | os.PathLike) -> TrainConfig:
    """The stored run's config; of ``given`` only batch size, preview and save intervals apply.

    Raises:
        InputError: the stored config does not parse, or ``given`` asks for another canvas size.
    """
    try:
        config = TrainConfig.from_dict(model.training["config"])
    except (KeyError, TypeError, ValueError) as exc:
        raise InputError(f"{path}: stored training config does not parse ({exc}); cannot resume") from None
    if given is None:
        return config
    if given.size != config.size:
        raise InputError(f"--size {given.size} differs from the model's {config.size}; cannot resume at another size")
    return replace(config, batch_size=given.batch_size, preview_every=given.preview_every,
                   save_every_s=given.save_every_s)


def restore(trainer: Trainer, rng: torch.Generator, model: ReferenceModel, path: str | os.PathLike) -> None:
    """Put the stored discriminator, optimisers, step and random state into ``trainer`` and ``rng``.

    Raises:
        InputError: the stored state does not fit the networks.
    """
    training = model.training or {}
    try:
        trainer.load_state_dict(training["trainer"])
        rng.set_state(training["rng"])
    except (KeyError, TypeError, ValueError, RuntimeError) as exc:
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else exc.__class__.__name__
        raise InputError(f"{path}: damaged training state ({first[:120]}); cannot resume") from None


def load_init(path: str | os.PathLike, config: TrainConfig) -> tuple[ReferenceModel, dict[str, Any] | None]:
    """A model to start a new run from (``--init``): its generator, and its discriminator's state when it kept one.

    Its generator must be the one ``config`` trains (same size, width, depth, inputs, pose layout): the
    weights are copied, not adapted, but for one case: a model whose generator does not read exemplars starts a
    run that does with the exemplar's input weights at zero (:func:`with_exemplar_input`), so it begins as
    that model and learns to use them.

    Raises:
        InputError: no such file, not a readable model, or another architecture.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"--init {path}: no such model")
    model = load_reference_model(path)
    differ = generator_differences(model, config)
    if not differ and config.exemplar and not model.sees_exemplar:
        model = with_exemplar_input(model)
    if differ:
        raise InputError(f"--init {path}: its generator differs from this run's: {', '.join(differ)}; "
                         "train with the same --size and options, or pass --init none")
    disc = ((model.training or {}).get("trainer") or {}).get("discriminator")
    if disc is not None and disc.get("config") != config.discriminator_config().to_dict():
        disc = None
    return model, disc


def with_exemplar_input(model: ReferenceModel) -> ReferenceModel:
    """``model`` with a generator that also reads an exemplar (three more input channels) whose weights are zero:
    its frames are the same whatever the exemplar."""
    config = model.generator_config
    grown = replace(config, in_channels=config.in_channels + FRAME_CHANNELS, exemplar=True)
    state = dict(model.generator_state)
    net = build_generator(model.generator_name, config)
    first = [f"downs.0.{n}" for n, p in net.downs[0].named_parameters() if p.dim() == 4]
    last = _last_conv(net.head)
    head = [f"head.{n}" for n, m in net.head.named_modules() if m is last]
    if len(first) != 1 or len(head) != 1:
        raise InputError("the model's generator has no single first and last convolution to widen for the exemplar")
    weight = state[first[0]]  # [C0, C_in, k, k]: zeros for the exemplar's channels
    state[first[0]] = torch.cat([weight, weight.new_zeros((weight.shape[0], FRAME_CHANNELS, *weight.shape[2:]))], 1)
    weight, bias = state[f"{head[0]}.weight"], state[f"{head[0]}.bias"]
    # the blend mask's output: zero weights and bias, a half-and-half blend to start from
    out_dim = 1 if isinstance(last, torch.nn.ConvTranspose2d) else 0
    shape = list(weight.shape)
    shape[out_dim] = 1
    state[f"{head[0]}.weight"] = torch.cat([weight, weight.new_zeros(shape)], out_dim)
    state[f"{head[0]}.bias"] = torch.cat([bias, bias.new_zeros(1)])
    return replace(model, generator_config=grown, generator_state=state)


def generator_differences(model: ReferenceModel, config: TrainConfig) -> list[str]:
    """How ``model``'s generator differs from the one a run of ``config`` trains (empty: it can start from it)."""
    want, have = config.generator_config().to_dict(), model.generator_config.to_dict()
    if want["exemplar"] and not have.get("exemplar"):  # widened to read one (with_exemplar_input)
        have = {**have, "exemplar": True, "in_channels": have["in_channels"] + FRAME_CHANNELS}
    differ = [f"{k} {have.get(k)} (wanted {v})" for k, v in want.items() if have.get(k) != v]
    if model.pose_layout != config.pose_layout:
        differ.append(f"pose layout {model.pose_layout} (wanted {config.pose_layout})")
    return differ


def strip_resume_state(model: ReferenceModel) -> ReferenceModel:
    """The model without what only resuming reads (the discriminator, both optimisers, the random state): it
    drives exactly as before and cannot be resumed. The run's record (steps, seconds, device, config) stays."""
    if model.training is None:
        return model
    record = {k: v for k, v in model.training.items() if k not in RESUME_STATE}
    return replace(model, training=record or None)


def write_stripped(path: str | os.PathLike, out: str | os.PathLike, overwrite: bool = False) -> tuple[Path, int, int]:
    """Write the model at ``path`` without its resume state to ``out`` (atomically; ``out`` may be ``path`` itself
    with ``overwrite``).

    Returns:
        ``out``, and the sizes in bytes of the model before and after.

    Raises:
        InputError: ``path`` is not a readable reference model, or ``out`` exists without ``overwrite``.
    """
    path, out = Path(path), Path(out)
    model = load_reference_model(path)
    before = path.stat().st_size
    save_reference_model(strip_resume_state(model), out, overwrite=overwrite)
    return out, before, out.stat().st_size
