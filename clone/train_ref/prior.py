"""A generator prior: the pose-to-frame generator (with its discriminator and face pass) trained on many synthetic
performers, so that a reference model can start from a network that has already seen many bodies, outfits, views
and poses (``clone train-ref --init PRIOR``).

The performers are the project's own (:mod:`clone.synth`: licence-clean): each is a random character (bones,
body shape, skin, hair, clothes), a random clip of the motion capture under ``--mocap``, a random view (front,
side and back) and backdrop (the synthetic room, or a plain studio wall for a share of them), sometimes with a
whole-body turn. Each is rendered larger than the canvas and cut to its own canvas exactly as `clone train-ref`
cuts a video, with its detailed (body31) poses where the renderer draws the face, hands and heels
(:mod:`clone.synth.details`), and its empty room as the background plate. All performers' frames form one
dataset (:class:`PerformerData`); a step samples across them.

The run is a `clone train-ref` run in every other way (same trainer, losses, schedule, checkpoint: ``--resume``
continues it from the same performers, which are drawn from the seed). :func:`export_prior` writes the compact
file: no optimiser state, float16 weights. The shipped one (:data:`PACKAGED_PRIOR`: one-colour shirts, measured in
docs/cloning.md) is where `clone train-ref` starts a model whose size and options it fits.
"""

from __future__ import annotations

import dataclasses
import logging
import os
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import Tensor

from clone.model.canvas import Canvas, choose_canvas, cut_frame, image_to_canvas
from clone.model.exemplar import choose_bank
from clone.model.reference import (
    DETAIL_LAYOUT,
    LAYOUT,
    load_reference_model,
    save_reference_model,
)
from clone.model.tensors import to_tensor
from clone.synth.appearance import Backdrop, get_character
from clone.synth.performance import performance_background, render_performance
from clone.train_ref.checkpoint import ReferenceInfo, load_init
from clone.train_ref.config import TrainConfig
from clone.train_ref.data import ReferenceData, track_summary
from clone.train_ref.state import ProgressFn, StepProgress, check_options, previous_and_config, start_run
from pose_io.errors import InputError
from pose_io.track import PoseTrack
from retarget.runtime import ThreadGrowth
from retarget.training import distributed
from retarget.world.build import find_mocap_files
from retarget.world.rigs import load_motion
from retarget.world.turns import draw_turn

log = logging.getLogger(__name__)

# The shipped prior (``export_prior`` of a `clone train-prior` run; how it was trained: docs/cloning.md).
PACKAGED_PRIOR = Path(__file__).resolve().parent.parent / "data" / "generator_prior_256.pt"


@dataclass(frozen=True)
class PriorConfig:
    """Which synthetic performers a prior trains on (all drawn from ``seed``).

    Attributes:
        performers: how many.
        frames: consecutive frames of each (30 frames/s).
        render_scale: each is rendered at this many times the canvas size and cut to its canvas (a video's
            person is cut out of a larger frame too).
        studio_share: share of the performers in front of a plain light wall instead of the synthetic room.
        turn_share: share of the performers who turn about (90-360 degrees) during their clip.
        plain_share: share of the performers whose shirt is one plain colour (the others keep their character's
            stripes or checks, which a prior learnt on them paints over a real reference as bands; measured in
            docs/cloning.md). A run stored before this field read as 0: its performers are the same again.
        seed: draws the performers.
    """

    performers: int = 128
    frames: int = 40
    render_scale: int = 2
    studio_share: float = 0.4
    turn_share: float = 0.3
    plain_share: float = 1.0
    seed: int = 0

    @classmethod
    def stored(cls, values: dict[str, Any]) -> PriorConfig:
        """The config a run stored (one from before ``plain_share`` drew every shirt as its character's)."""
        return cls(**{"plain_share": 0.0, **values})

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)


class PerformerData(ReferenceData):
    """Many performers' frames as one training set: each frame's predecessor is within its own clip, and each
    sample gets its own performer's background plate.

    Attributes (besides :class:`ReferenceData`'s):
        owner: [N] int, the performer of each frame.
        first: [N] bool, the first frame of a performer's clip (it has no predecessor).
        performer_plates: [P, S, S, 3] uint8 RGB, each performer's empty background on its canvas.
    """

    def __init__(self, frames: np.ndarray, joints: np.ndarray, owner: np.ndarray, plates: np.ndarray, size: int,
                 layout: str = DETAIL_LAYOUT, faces: bool = True) -> None:
        super().__init__(frames, joints, np.ones(len(frames), dtype=bool), size, plate=plates[0], layout=layout,
                         faces=faces)
        self.owner = np.asarray(owner, dtype=np.int64)
        self.first = np.r_[True, self.owner[1:] != self.owner[:-1]]
        self.performer_plates = plates

    def previous(self, idx: np.ndarray) -> np.ndarray:
        return np.where(self.first[idx], -1, idx - 1)

    def groups(self) -> np.ndarray:
        return self.owner

    def plates(self, idx: np.ndarray) -> Tensor:
        return to_tensor(self.performer_plates[self.owner[idx]])


def _studio(rng: np.random.Generator) -> Backdrop:
    """A plain light wall and floor, as in a studio (white to light grey, a little warm or cool)."""
    v = float(rng.uniform(215, 252))
    tint = rng.uniform(-6, 6, size=3)
    wall = tuple(int(np.clip(v + t, 0, 255)) for t in tint)
    floor = tuple(int(np.clip(v - 12 + t, 0, 255)) for t in tint)
    return Backdrop(wall_top=wall, wall_bottom=wall, floor_near=floor, floor_far=floor,
                    texture_seed=int(rng.integers(1 << 30)), board_width=1.0)


def render_performers(mocap: str | os.PathLike, config: PriorConfig, size: int, train: TrainConfig,
                      progress: ProgressFn | None = None) -> tuple[PerformerData, PoseTrack]:
    """Render the prior's performers and cut each to its own canvas.

    Args:
        mocap: a folder of motion capture (BVH, AMC), searched recursively.
        config: which performers.
        size: the canvas size.
        train: the run's settings (canvas mode and margin, pose layout, whether faces are needed).
        progress: called after each performer (phase ``"rendering"``).

    Returns:
        The training set, and every performer's body15 track on its canvas one after the other (the model's
        record of what it trained on).

    Raises:
        InputError: no motion capture under ``mocap``, or no clip there readable and ``frames`` long.
    """
    files = find_mocap_files(Path(mocap))
    if not files:
        raise InputError(f"--mocap {mocap}: no .bvh, .bvh.gz or .amc files under it")
    rng = np.random.default_rng([config.seed, 0x9121])
    shirts = np.random.default_rng([config.seed, 0x9122])  # its own stream: the share changes shirts, nothing else
    render = size * config.render_scale
    n, f = config.performers, config.frames
    frames = np.zeros((n * f, size, size, 3), dtype=np.uint8)
    joints: list[np.ndarray] = []
    body: list[np.ndarray] = []
    plates = np.zeros((n, size, size, 3), dtype=np.uint8)
    started = time.perf_counter()
    motions: dict[Path, Any] = {}  # each clip read once; None: unreadable or shorter than ``frames``
    i = 0
    while i < n:
        path = files[int(rng.integers(len(files)))]
        if path not in motions:
            try:
                motion = load_motion(path)
            except InputError as exc:  # a rig the world cannot map
                log.info("skipping %s: %s", path, exc)
                motion = None
            motions[path] = motion if motion is not None and motion.num_frames >= f else None
            if len(motions) == len(files) and not any(m is not None for m in motions.values()):
                raise InputError(f"--mocap {mocap}: no clip there is readable and {f} frames long")
        motion = motions[path]
        if motion is None:
            continue
        skeleton, look, _ = get_character(str(int(rng.integers(1 << 20))))
        if rng.random() < config.studio_share:
            look = replace(look, backdrop=_studio(rng))
        if shirts.random() < config.plain_share:
            look = replace(look, pattern="plain")
        yaw, pitch = float(rng.uniform(-180, 180)), float(rng.uniform(-8, 15))
        start = int(rng.integers(motion.num_frames - f + 1))
        turn = draw_turn(rng, f) if rng.random() < config.turn_share else None
        stream, track, _ = render_performance(motion, skeleton, look, yaw, pitch, render, start, f, turn=turn,
                                              details=train.pose_layout == DETAIL_LAYOUT)
        body15 = track.to_layout(LAYOUT).joints
        canvas = choose_canvas(body15, track.image_size, size, train.canvas_mode, train.canvas_margin)
        for t, frame in enumerate(stream):
            frames[i * f + t] = cut_frame(frame, canvas)
        plates[i] = cut_frame(performance_background(look, yaw, pitch, render), canvas)
        joints.append(image_to_canvas(track.joints, canvas))
        body.append(image_to_canvas(body15, canvas))
        i += 1
        if progress is not None:
            progress(StepProgress("rendering", i, n, time.perf_counter() - started, None, {}))
    owner = np.repeat(np.arange(n), f)
    data = PerformerData(frames, np.concatenate(joints), owner, plates, size, layout=train.pose_layout,
                         faces=train.uses_faces)
    body_joints = np.concatenate(body).astype(np.float32)
    record = PoseTrack(body_joints, np.isfinite(body_joints[..., 0]).astype(np.float32), 30.0, (size, size), LAYOUT)
    return data, record


def train_prior(
    mocap: str | os.PathLike,
    out: str | os.PathLike,
    *,
    config: TrainConfig | None = None,
    prior: PriorConfig | None = None,
    steps: int | None = None,
    minutes: float | None = None,
    device: torch.device | str = "cpu",
    resume: bool = False,
    overwrite: bool = False,
    progress: ProgressFn | None = None,
    grow_threads: bool = False,
    init: str | os.PathLike | None = None,
) -> tuple[Path, int]:
    """Train (or continue) a generator prior on synthetic performers; the model file at ``out`` keeps the full
    training state (``resume`` continues it); :func:`export_prior` makes the compact file.

    Args:
        mocap: a folder of motion capture.
        out: the model file (with its training state).
        config: the generator's run settings (default ``TrainConfig(size=256)``); resuming takes the stored ones.
        prior: the performers (default ``PriorConfig()``); resuming takes the stored ones.
        steps: stop at this many steps in all; minutes: stop after this many minutes of this call.
        device: where to train.
        resume, overwrite: continue the model at ``out``, or replace it.
        progress: called after every performer rendered and every step.
        grow_threads: raise torch's threads whenever more cores come free (CPU).
        init: a new run starts from the networks of this model or compact prior (whose optimiser state is not
            kept: an exported prior is continued this way); see :func:`clone.train_ref.checkpoint.load_init`.

    Returns:
        ``(out, steps in all)``.
    """
    from clone.train_ref.loop import _train_steps
    from clone.train_ref.preview import preview_rows

    out = Path(out)
    check_options(resume, overwrite, steps, minutes)
    if not resume:
        # a prior continued from --init is a long run, not a minutes-long fine-tune: it keeps the prior's own
        # learning rate (TrainConfig.init_lr was chosen for references started from the prior)
        config = replace(config or TrainConfig(size=256), init_lr=None)
    previous, config = previous_and_config(out, config, resume, overwrite)
    if previous is not None:
        stored = ((previous.training or {}).get("prior") or {})
        prior = PriorConfig.stored(stored) if stored else (prior or PriorConfig())
    prior = prior or PriorConfig()
    if init is not None and resume:
        raise InputError("--init starts a new prior run; --resume continues one: pass only one of them")
    start = load_init(init, config) if init is not None else None
    if steps is None and minutes is None:
        steps = config.steps
    device = torch.device(device)
    data, record = render_performers(mocap, prior, config.size, config, progress)
    if config.exemplar:  # every frame is in the bank; a frame's exemplar is its own performer's, a quarter clip away
        data.set_exemplars(choose_bank(data.frames, data.joints, data.usable, max_count=len(data.frames)),
                           gap=max(1, prior.frames // 4))
    canvas = Canvas(x0=0, y0=0, side=config.size, size=config.size, image_size=(config.size, config.size))
    details = None
    if config.pose_layout == DETAIL_LAYOUT:
        details = PoseTrack(data.joints, np.isfinite(data.joints[..., 0]).astype(np.float32), 30.0,
                            (config.size, config.size), DETAIL_LAYOUT)
    reference = ReferenceInfo(canvas, None, record, track_summary(record, np.ones(record.num_frames, bool)), None,
                              None, None, plate=data.plate, details=details,
                              face_radius=data.face_radius if config.face_pass else None, prior=prior.to_dict())
    run = start_run(out, reference, config, device=device, previous=previous, progress=progress,
                    world=distributed.World(), part=None, init=start)
    with torch.enable_grad():
        run.started = time.perf_counter()
        grow = ThreadGrowth() if grow_threads and device.type == "cpu" else None
        _train_steps(run, data, preview_rows(data.indices), steps, minutes * 60.0 if minutes else None, grow)
        run.save()
    return out, run.trainer.step_count


def export_prior(path: str | os.PathLike, out: str | os.PathLike, overwrite: bool = False) -> Path:
    """The compact prior of a prior run's model file: the generator, the face pass and the discriminator in
    float16, the run's record, no optimiser state (``clone train-ref --init`` reads it like any model).

    Raises:
        InputError: ``path`` is not a prior run's model.
    """
    model = load_reference_model(path)
    training = dict(model.training or {})
    if "prior" not in training:
        raise InputError(f"{path}: not a generator prior's model (train one with `clone train-prior`)")
    trainer = training.get("trainer") or {}
    disc = trainer.get("discriminator")
    kept = {k: v for k, v in training.items() if k not in ("trainer", "rng")}
    if disc is not None:
        kept["trainer"] = {"discriminator": {**disc, "state_dict": _half(disc["state_dict"])}}
    face_pass = model.face_pass
    if face_pass is not None:
        face_pass = {**face_pass, "state_dict": _half(face_pass["state_dict"])}
    compact = replace(model, generator_state=_half(model.generator_state), face_pass=face_pass, training=kept)
    save_reference_model(compact, out, overwrite=overwrite)
    return Path(out)


def matching_prior(config: TrainConfig, path: str | os.PathLike | None = None) -> Path | None:
    """The generator prior at ``path`` (default: the shipped one) when a run of ``config`` can start from it
    (the same generator and pose layout, see :func:`clone.train_ref.checkpoint.load_init`), else None."""
    from clone.train_ref.checkpoint import generator_differences

    path = Path(path) if path is not None else PACKAGED_PRIOR
    if not path.is_file():
        return None
    try:
        model = load_reference_model(path)
    except InputError:
        return None
    return None if generator_differences(model, config) else path


def _half(state: dict[str, Tensor]) -> dict[str, Tensor]:
    """Floating-point tensors as float16 (loading copies them back into float32 parameters)."""
    return {k: v.half() if v.is_floating_point() else v for k, v in state.items()}
