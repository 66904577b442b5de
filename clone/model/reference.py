"""The reference model: ONE file holding everything `clone drive` needs about the reference person.

Contents (a plain dict saved with ``torch.save`` and loaded with ``weights_only=True``):

- ``kind`` = ``"clone2d-reference"``, ``format_version``
- ``generator``: registry name, config dict, ``state_dict`` of the unwrapped network
- ``canvas``: where the generator's square canvas sits in the reference's frame
- ``scale_stats``: feet range and heights for global scaling (Everybody Dance Now)
- ``reference_track``: the reference's body15 track (joints, confidence, fps, image size), so codes can be
  recomputed later with other retargeting weights
- ``track_summary``: frame counts, visible fractions, median bone lengths (for reports)
- ``reference_codes``: ``ReferenceCodes.to_dict()`` of the retargeting network, or None; ``codes_weights``:
  the SHA-256 of the weights file that made them, ``codes_weights_path`` where that file was
- ``pose_layout`` (optional, default ``body15``): the layout the pose maps are drawn in (``body31``: with face,
  hands and feet)
- ``background``: ``{"plate": [S, S, 3] uint8}``, the reference's background plate on the canvas
  (:mod:`clone.model.background`), or None; a generator with ``alpha`` or ``plate_input`` composites over it
- ``face_pass`` (optional): ``{"config", "state_dict", "radius"}``, the face pass (:mod:`clone.model.face`): its
  U-Net's config and weights and the reference's face radius on the canvas; `clone drive` runs it after the
  generator. Files without it drive as before.
- ``exemplars`` (optional): the bank of reference frames a generator that sees exemplars takes them from
  (:mod:`clone.model.exemplar`: JPEG frames on the canvas, their joints and frame numbers).
- ``training`` (optional): the run's record and resume state, written by `clone train-ref` atomically with
  the weights: ``steps``, ``seconds``, ``device``, ``config`` (the ``TrainConfig`` as a dict), ``trainer``
  (discriminator, both optimisers, step; the face pass's optimiser and discriminator) and ``rng`` (the run's
  random state). A file without it drives as well but cannot be resumed.

Format versions: 3 adds ``background``; 2 keeps the training state in the file under ``training``; 1 kept only the record there
(steps, seconds, config, device), with the state in a sibling ``<model>.state`` file. Version 1 files still
load (and drive); they cannot be resumed. Version 1 and 2 files have no plate and drive as they did.
"""

from __future__ import annotations

import hashlib
import logging
import os
import pickle
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch

from clone.model.canvas import Canvas
from clone.model.exemplar import ExemplarBank
from clone.model.face import FacePass
from clone.model.networks import GeneratorConfig, UNetGenerator, build_generator
from clone.model.tensors import to_tensor
from pose_io.atomic import atomic_file
from pose_io.errors import InputError
from pose_io.track import PoseTrack
from retarget.baselines.global_scale import ScaleStats

log = logging.getLogger(__name__)

KIND = "clone2d-reference"
FORMAT_VERSION = 3
LAYOUT = "body15"
DETAIL_LAYOUT = "body31"
POSE_LAYOUTS = (LAYOUT, DETAIL_LAYOUT)  # what pose maps can show: the network's joints, or with the details


@dataclass(frozen=True, eq=False)
class ReferenceModel:
    """What a trained reference model file holds (see the module docstring).

    Attributes:
        generator_name: key into ``clone.model.networks.GENERATORS``.
        generator_config: the generator's architecture.
        generator_state: its ``state_dict`` (CPU tensors).
        canvas: the canvas it works on.
        scale_stats: the reference's feet range and heights (None when it never shows its ankles).
        reference_track: the reference's body15 track in its image pixels.
        track_summary: plain-data summary of the reference's poses.
        reference_codes: the retargeting network's codes of the reference (plain arrays), or None.
        codes_weights: SHA-256 of the retargeting weights that made ``reference_codes``, or None.
        codes_weights_path: where those weights were (a hint for `clone drive` when no --weights is given).
        training: the training run's record and resume state (see the module docstring), or None.
        temporal: whether the generator takes the previous frame.
        plate: [S, S, 3] uint8 RGB background plate on the canvas, or None (a model trained without one).
        pose_layout: the layout its pose maps are drawn in: ``body15`` (files before detailed maps) or
            ``body31`` (with face, hands and feet; :mod:`clone.model.detail_map`).
        face_pass: ``{"config": GeneratorConfig dict, "state_dict", "radius": canvas pixels}`` of the face pass
            (:mod:`clone.model.face`), or None.
        exemplars: the bank of reference frames the generator's exemplars come from (:mod:`clone.model.exemplar`),
            or None (a generator that sees none, or a prior).
    """

    generator_name: str
    generator_config: GeneratorConfig
    generator_state: dict[str, torch.Tensor]
    canvas: Canvas
    scale_stats: ScaleStats | None
    reference_track: PoseTrack
    track_summary: dict[str, Any]
    reference_codes: dict[str, Any] | None = None
    codes_weights: str | None = None
    codes_weights_path: str | None = None
    training: dict[str, Any] | None = None
    temporal: bool = True
    plate: np.ndarray | None = None
    pose_layout: str = LAYOUT
    face_pass: dict[str, Any] | None = None
    exemplars: ExemplarBank | None = None

    def build_generator(self, device: torch.device | str = "cpu") -> UNetGenerator:
        """The generator with its weights, in eval mode on ``device``."""
        net = build_generator(self.generator_name, self.generator_config)
        net.load_state_dict(self.generator_state)
        return net.to(device).eval()

    def face_pass_net(self, device: torch.device | str = "cpu") -> UNetGenerator | None:
        """The face pass's U-Net with its weights, in eval mode on ``device``; None for a model without one."""
        if self.face_pass is None:
            return None
        net = UNetGenerator(GeneratorConfig.from_dict(self.face_pass["config"]))
        net.load_state_dict(self.face_pass["state_dict"])
        return net.to(device).eval()

    def build_face_pass(self, device: torch.device | str = "cpu") -> FacePass | None:
        """The face pass ready to drive (:class:`clone.model.face.FacePass`), or None for a model without one."""
        net = self.face_pass_net(device)
        return None if net is None else FacePass(net, float(self.face_pass["radius"]))

    @property
    def sees_exemplar(self) -> bool:
        """Whether the generator reads an exemplar (:attr:`GeneratorConfig.exemplar`)."""
        return self.generator_config.exemplar

    def plate_tensor(self, device: torch.device | str = "cpu") -> torch.Tensor | None:
        """The background plate as the generator takes it, [1, 3, S, S] in [-1, 1] on ``device``; None without one."""
        return None if self.plate is None else to_tensor(self.plate[None]).to(device)


def preview_path(model_path: str | os.PathLike) -> Path:
    """Where training previews of ``model_path`` go: ``<model stem>.preview.png``."""
    p = Path(model_path)
    return p.with_name(p.stem + ".preview.png")


def file_sha256(path: str | os.PathLike) -> str:
    """Hex SHA-256 of a file's bytes (identifies the retargeting weights that made stored codes)."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _to_storable(obj: Any) -> Any:
    """numpy arrays -> tensors, recursively, so ``weights_only`` loading accepts them."""
    if isinstance(obj, np.ndarray):
        return torch.from_numpy(np.ascontiguousarray(obj).copy())
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, dict):
        return {str(k): _to_storable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_to_storable(v) for v in obj]
    return obj


def _to_cpu(obj: Any) -> Any:
    """Tensors -> detached CPU tensors, recursively; keys, lists and tuples stay as they are."""
    if isinstance(obj, torch.Tensor):
        return obj.detach().cpu()
    if isinstance(obj, dict):
        return {k: _to_cpu(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return type(obj)(_to_cpu(v) for v in obj)
    return obj


def _from_storable(obj: Any) -> Any:
    """Tensors -> numpy arrays, recursively (inverse of :func:`_to_storable`)."""
    if isinstance(obj, torch.Tensor):
        return obj.numpy()
    if isinstance(obj, dict):
        return {k: _from_storable(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_from_storable(v) for v in obj]
    return obj


def _track_to_dict(track: PoseTrack) -> dict[str, Any]:
    return {
        "joints": torch.from_numpy(track.joints.copy()),
        "confidence": torch.from_numpy(track.confidence.copy()),
        "fps": track.fps,
        "image_size": list(track.image_size),
        "layout": track.layout,
    }


def _track_from_dict(d: dict[str, Any]) -> PoseTrack:
    return PoseTrack(
        d["joints"].numpy(), d["confidence"].numpy(), float(d["fps"]), tuple(d["image_size"]), str(d["layout"])
    )


def save_reference_model(model: ReferenceModel, path: str | os.PathLike, overwrite: bool = True) -> Path:
    """Write ``model`` to ``path`` atomically; returns the path."""
    payload = {
        "kind": KIND,
        "format_version": FORMAT_VERSION,
        "generator": {
            "name": model.generator_name,
            "config": model.generator_config.to_dict(),
            "state_dict": {k: v.detach().cpu().clone() for k, v in model.generator_state.items()},
        },
        "temporal": model.temporal,
        "canvas": model.canvas.to_dict(),
        "scale_stats": None if model.scale_stats is None else model.scale_stats.to_dict(),
        "reference_track": _track_to_dict(model.reference_track),
        "track_summary": _to_storable(model.track_summary),
        "reference_codes": None if model.reference_codes is None else _to_storable(model.reference_codes),
        "codes_weights": model.codes_weights,
        "codes_weights_path": model.codes_weights_path,
        "background": None if model.plate is None else {"plate": torch.from_numpy(model.plate.copy())},
        "pose_layout": model.pose_layout,
    }
    if model.face_pass is not None:
        payload["face_pass"] = {
            "config": dict(model.face_pass["config"]),
            "state_dict": {k: v.detach().cpu().clone() for k, v in model.face_pass["state_dict"].items()},
            "radius": float(model.face_pass["radius"]),
        }
    if model.exemplars is not None:
        payload["exemplars"] = model.exemplars.to_storable()
    if model.training is not None:
        # As it is: optimiser states have int keys and tensors that _to_storable would change.
        payload["training"] = _to_cpu(model.training)
    path = Path(path)
    with atomic_file(path, overwrite=overwrite) as tmp:
        torch.save(payload, tmp)
    return path


def load_checkpoint_dict(path: str | os.PathLike, kind: str) -> dict[str, Any]:
    """Load a clone2d file of ``kind`` safely; anything else raises InputError with one line.

    Checks: the file exists, is a torch file that loads with ``weights_only=True``, is a dict of ``kind``,
    and has a format version this code knows.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: no such file")
    try:
        data = torch.load(path, map_location="cpu", weights_only=True)
    except (pickle.UnpicklingError, zipfile.BadZipFile, RuntimeError, EOFError, ValueError, OSError) as exc:
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else exc.__class__.__name__
        raise InputError(f"{path}: not a readable clone2d {kind} file ({first[:120]})") from None
    if not isinstance(data, dict) or data.get("kind") != kind:
        found = data.get("kind") if isinstance(data, dict) else type(data).__name__
        raise InputError(f"{path}: not a clone2d {kind} file (kind {found!r})")
    version = data.get("format_version")
    if not isinstance(version, int) or version > FORMAT_VERSION or version < 1:
        raise InputError(
            f"{path}: {kind} format version {version!r} is not supported by this clone2d "
            f"(supports up to {FORMAT_VERSION}); update clone2d or retrain"
        )
    return data


def _training(training: Any) -> dict[str, Any] | None:
    """The stored ``training`` entry: a dict, or None when the file has none."""
    if training is not None and not isinstance(training, dict):
        raise TypeError(f"training entry is a {type(training).__name__}, not a dict")
    return training


def _plate(background: Any, config: GeneratorConfig, canvas: Canvas) -> np.ndarray | None:
    """The stored plate, checked against the generator that needs it and the canvas it belongs to."""
    if background is None:
        if config.uses_plate:
            raise ValueError("the generator composites over a background plate, but the file holds none")
        return None
    if not isinstance(background, dict) or not isinstance(background.get("plate"), torch.Tensor):
        raise TypeError("background entry is not a dict holding a plate tensor")
    plate = background["plate"].numpy()
    if plate.dtype != np.uint8 or plate.shape != (canvas.size, canvas.size, 3):
        raise ValueError(f"background plate is {plate.dtype} {tuple(plate.shape)}, not uint8 "
                         f"({canvas.size}, {canvas.size}, 3)")
    return plate


def _face_pass(entry: Any) -> dict[str, Any] | None:
    """The stored face pass entry, checked for its parts (its weights are checked by building it)."""
    if entry is None:
        return None
    if not isinstance(entry, dict) or any(k not in entry for k in ("config", "state_dict", "radius")):
        raise TypeError("face_pass entry is not a dict of config, state_dict and radius")
    radius = float(entry["radius"])
    if not np.isfinite(radius) or radius <= 0:
        raise ValueError(f"face_pass radius {radius!r} is not a positive number")
    return {"config": dict(entry["config"]), "state_dict": dict(entry["state_dict"]), "radius": radius}


def _pose_layout(name: Any) -> str:
    if name not in POSE_LAYOUTS:
        raise ValueError(f"pose maps in an unknown layout {name!r}")
    return str(name)


def load_reference_model(path: str | os.PathLike) -> ReferenceModel:
    """Read a reference model written by :func:`save_reference_model`.

    Raises:
        InputError: missing, corrupt, foreign or newer file, or one whose contents do not rebuild a generator.
    """
    data = load_checkpoint_dict(path, KIND)
    try:
        gen = data["generator"]
        config = GeneratorConfig.from_dict(gen["config"])
        canvas = Canvas.from_dict(data["canvas"])
        model = ReferenceModel(
            generator_name=str(gen["name"]),
            generator_config=config,
            generator_state=dict(gen["state_dict"]),
            canvas=canvas,
            scale_stats=None if data.get("scale_stats") is None else ScaleStats.from_dict(data["scale_stats"]),
            reference_track=_track_from_dict(data["reference_track"]),
            track_summary=_from_storable(data.get("track_summary", {})),
            reference_codes=None if data.get("reference_codes") is None else _from_storable(data["reference_codes"]),
            codes_weights=data.get("codes_weights"),
            codes_weights_path=data.get("codes_weights_path"),
            training=_training(data.get("training")),
            temporal=bool(data.get("temporal", True)),
            plate=_plate(data.get("background"), config, canvas),
            pose_layout=_pose_layout(data.get("pose_layout", LAYOUT)),
            face_pass=_face_pass(data.get("face_pass")),
            exemplars=None if data.get("exemplars") is None else ExemplarBank.from_storable(data["exemplars"],
                                                                                            canvas.size),
        )
        # a prior has none: a reference started from it chooses its own
        if model.sees_exemplar and model.exemplars is None and "prior" not in (model.training or {}):
            raise ValueError("the generator reads exemplars, but the file holds no exemplar frames")
        model.build_generator("cpu")  # fails here, not mid-drive, when the weights do not fit the config
        model.face_pass_net("cpu")
    except (KeyError, TypeError, ValueError, RuntimeError) as exc:
        if isinstance(exc, InputError):
            raise
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else exc.__class__.__name__
        raise InputError(f"{path}: damaged reference model ({first[:120]})") from None
    return model
