"""The generator in int8 on ONNX Runtime: `clone drive --runtime int8`, what ``auto`` picks on a CPU with the
``fast`` extra.

The fp32 export (:func:`clone.runtime.onnx.export_onnx`) is statically quantised by ONNX Runtime (QDQ,
per-channel, activations uint8, weights int8), its activation ranges calibrated on a fp32 rollout over the
first frames of the model's own reference track, drawn and fed back as :func:`clone.runtime.generate.generate_frames`
does. On the 256² demo model (1 thread) it ran 1.96x the fp32 session (80 against 41 frames/s) and lost
0.0028-0.0030 SSIM against the ground truth of the three held-out pairs (README, "Cloning on a laptop").

Quantising takes about 3 s, so the result is cached under ``~/.cache/clone2d/generators/``, keyed by a hash of
everything that decides it (:func:`cache_key`); the most recently used models up to ``MAX_CACHE_BYTES`` are kept.
A cache file that does not read back is rebuilt; a failed quantisation, or one whose frames stray from fp32's on
the calibration frames, falls back to the fp32 session with a warning: driving never fails for it.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import shutil
import tempfile
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import torch

from clone.model.networks import generator_input
from clone.model.reference import ReferenceModel
from clone.model.tensors import to_tensor
from clone.runtime.onnx import OnnxGenerator
from clone.runtime.pose_maps import draw_inputs
from pose_io.atomic import atomic_file, mark_used, prune_lru
from pose_io.errors import raise_if_interrupted

log = logging.getLogger(__name__)

CACHE_FORMAT = 1  # bump when the file layout or what enters the key changes
MAGIC = b"clone2d-int8\n"  # then the payload's SHA-256 (32 bytes), then the ONNX model
MIN_FREE_FACTOR = 10  # cache only with this many times the file's size free on the disk
# The cache keeps its most recently used models up to this many bytes (every trained model adds one: about 3 MB
# at 256²); the least recently used are deleted when a new one is written.
MAX_CACHE_BYTES = 256 * 2**20


@dataclass(frozen=True)
class QuantConfig:
    """How the generator is quantised (every field enters the cache key).

    Attributes:
        frames: calibration frames: the first ``frames`` of the reference track, rolled out in fp32.
        per_channel: one weight scale per output channel.
        activations, weights: ONNX Runtime ``QuantType`` names.
        max_mean_abs_diff: the int8 frames may differ from fp32's by at most this mean on [-1, 1] over the
            calibration frames (each made from the same input); above it the fp32 session is used.
    """

    frames: int = 24
    per_channel: bool = True
    activations: str = "QUInt8"
    weights: str = "QInt8"
    max_mean_abs_diff: float = 0.05


def generator_cache_dir() -> Path:
    """``~/.cache/clone2d/generators``: beside the motion world's cache, under the same root."""
    from retarget.world.config import default_cache_dir

    return default_cache_dir().parent / "generators"


def cache_key(model: ReferenceModel, config: QuantConfig) -> str:
    """Hex SHA-256 of what decides the quantised model: the generator (name, config, every state tensor), the
    plate, the canvas, the calibration poses, the quantisation settings and the library versions."""
    import onnx
    import onnxruntime

    calibration = model.reference_track.frames(0, min(config.frames, model.reference_track.num_frames))
    h = hashlib.sha256()
    h.update(json.dumps({
        "format": CACHE_FORMAT, "generator": model.generator_name, "config": model.generator_config.to_dict(),
        "temporal": model.temporal, "canvas": model.canvas.to_dict(), "quant": asdict(config),
        "layout": calibration.layout, "versions": [onnxruntime.__version__, onnx.__version__, torch.__version__],
    }, sort_keys=True, default=str).encode())
    for name in sorted(model.generator_state):
        tensor = model.generator_state[name].detach().cpu().contiguous()
        h.update(f"{name} {tensor.dtype} {tuple(tensor.shape)}".encode())
        h.update(tensor.reshape(-1).view(torch.uint8).numpy().tobytes())  # raw bytes, whatever the dtype
    bank = model.exemplars
    for array in (model.plate, calibration.joints, calibration.confidence, None if bank is None else bank.joints,
                  None if bank is None else bank.images):
        h.update(b"none" if array is None else np.ascontiguousarray(array).tobytes())
    return h.hexdigest()


def calibration_feeds(model: ReferenceModel, fp32: OnnxGenerator,
                      config: QuantConfig) -> tuple[list[dict[str, np.ndarray]], list[np.ndarray]]:
    """The generator's inputs and fp32 outputs over the first frames of the reference track.

    Returns:
        ``(feeds, frames)``: per frame, ONNX Runtime's input dict (``x`` [1, C_in, S, S], ``plate``) and the fp32
        output [1, 3, S, S] in [-1, 1]; a temporal generator gets its own previous output, as when driving.
    """

    track = model.reference_track.frames(0, min(config.frames, model.reference_track.num_frames))
    drawn = list(draw_inputs(model, track))
    maps = np.concatenate([m for m, _ in drawn])  # [N, S, S, 3] uint8
    seen = None if drawn[0][1] is None else to_tensor(np.concatenate([e for _, e in drawn]))  # [N, 3, S, S]
    plate = model.plate_tensor("cpu") if fp32.with_plate else None  # [1, 3, S, S]
    size = model.canvas.size
    prev = torch.zeros(1, 3, size, size)  # no previous frame yet: zeros, as in generate_frames
    feeds, frames = [], []
    with torch.inference_mode():
        pose = to_tensor(maps)  # [N, 3, S, S]
        for i in range(len(pose)):
            ex = None if seen is None else seen[i:i + 1]
            x = generator_input(pose[i:i + 1], prev if model.temporal else None, ex)  # [1, C_in, S, S]
            out = fp32(x, plate)  # [1, 3, S, S]
            feed = {"x": x.numpy().copy()}
            if plate is not None:
                feed["plate"] = plate.numpy()
            feeds.append(feed)
            frames.append(out.numpy())
            prev = out
    return feeds, frames


def quantize(onnx_model: bytes, feeds: list[dict[str, np.ndarray]], config: QuantConfig) -> bytes:
    """The fp32 ONNX model statically quantised (QDQ), calibrated on ``feeds``; files only in a temp folder."""
    from onnxruntime.quantization import CalibrationDataReader, QuantFormat, QuantType, quantize_static
    from onnxruntime.quantization.shape_inference import quant_pre_process

    class Reader(CalibrationDataReader):
        def __init__(self) -> None:
            self.feeds = iter(feeds)

        def get_next(self) -> dict[str, np.ndarray] | None:
            return next(self.feeds, None)

    with tempfile.TemporaryDirectory(prefix="clone2d-int8-") as tmp:
        fp32, pre, out = (os.path.join(tmp, name) for name in ("fp32.onnx", "pre.onnx", "int8.onnx"))
        Path(fp32).write_bytes(onnx_model)
        # ONNX shape inference + graph optimisation, as ONNX Runtime asks (the symbolic pass is for transformers
        # and stops at the dynamic batch axis)
        quant_pre_process(fp32, pre, skip_symbolic_shape=True)
        quantize_static(pre, out, Reader(), quant_format=QuantFormat.QDQ, per_channel=config.per_channel,
                        activation_type=QuantType[config.activations], weight_type=QuantType[config.weights],
                        # instance norm's scale is 1-D: its channels are axis 0 (ONNX Runtime assumes 1 and warns)
                        extra_options={"QDQOpTypePerChannelSupportToAxis": {"InstanceNormalization": 0}})
        return Path(out).read_bytes()


def read_cached(path: Path) -> bytes | None:
    """The model stored at ``path``, or None when there is none or it does not check out."""
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        return None
    except OSError as exc:
        log.warning("cannot read the cached int8 generator %s (%s); rebuilding it", path, exc)
        return None
    head = len(MAGIC) + 32
    if data[:len(MAGIC)] != MAGIC or hashlib.sha256(data[head:]).digest() != data[len(MAGIC):head]:
        log.warning("the cached int8 generator %s is damaged; rebuilding it", path)
        return None
    return data[head:]


def write_cached(path: Path, model: bytes) -> None:
    """Store ``model`` at ``path`` atomically; skipped with a log line when the disk is nearly full or
    the folder cannot be written (the cache only saves time)."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        free = shutil.disk_usage(path.parent).free
        if free < MIN_FREE_FACTOR * len(model):
            log.warning("not caching the int8 generator: %.1f MB free in %s, %d MB wanted; the next drive "
                        "quantises again", free / 1e6, path.parent, MIN_FREE_FACTOR * len(model) // 10**6)
            return
        with atomic_file(path) as tmp:
            tmp.write_bytes(MAGIC + hashlib.sha256(model).digest() + model)
        prune_cache(path.parent, keep=path, max_bytes=MAX_CACHE_BYTES)
    except OSError as exc:
        log.warning("not caching the int8 generator in %s (%s)", path.parent, exc)


def prune_cache(folder: Path, keep: Path, max_bytes: int = MAX_CACHE_BYTES) -> list[Path]:
    """Delete the least recently used ``*.int8.onnx`` in ``folder`` until the rest fit (``keep`` stays)."""
    return prune_lru(folder, "*.int8.onnx", keep, max_bytes, "int8 cache")


def build_int8_generator(model: ReferenceModel, threads: int | None = None, cache_dir: Path | None = None,
                         config: QuantConfig = QuantConfig()) -> OnnxGenerator:
    """The model's generator on ONNX Runtime in int8, from the cache when it is there; else the fp32 session.

    Args:
        model: the reference model.
        threads: ONNX Runtime's intra-op threads (default: torch's).
        cache_dir: where quantised models are kept (default :func:`generator_cache_dir`).
        config: how to quantise.

    Returns:
        An :class:`OnnxGenerator` whose ``precision`` says ``int8``, or ``fp32`` when quantisation failed.
    """
    with_plate = model.generator_config.uses_plate
    path = (cache_dir or generator_cache_dir()) / f"{cache_key(model, config)}.int8.onnx"
    cached = read_cached(path)
    if cached is not None:
        try:
            generator = OnnxGenerator.from_onnx(cached, with_plate, threads, precision="int8")
            log.info("int8 generator from the cache: %s", path)
            mark_used(path)  # prune_cache deletes the least recently used
            return generator
        except Exception as exc:  # noqa: BLE001 - any unreadable model is rebuilt
            raise_if_interrupted(exc)
            log.warning("the cached int8 generator %s does not load (%s); rebuilding it", path, exc)
    fp32 = OnnxGenerator(model.build_generator("cpu"), model.canvas.size, with_plate, threads)
    try:
        feeds, frames = calibration_feeds(model, fp32, config)
        generator = OnnxGenerator.from_onnx(quantize(fp32.onnx, feeds, config), with_plate, threads, "int8")
        diff = float(np.mean([np.abs(generator.session.run(None, feed)[0] - frame).mean()
                              for feed, frame in zip(feeds, frames)]))
    except Exception as exc:  # noqa: BLE001 - driving goes on in fp32, whatever broke
        raise_if_interrupted(exc)
        log.warning("int8 quantisation of the generator failed (%s: %s); running it in fp32",
                    type(exc).__name__, str(exc).strip().splitlines()[0][:200] if str(exc).strip() else "")
        return fp32
    if diff > config.max_mean_abs_diff:
        log.warning("the int8 generator's frames differ from fp32's by %.3f on average (more than %.3f); "
                    "running it in fp32", diff, config.max_mean_abs_diff)
        return fp32
    log.info("generator quantised to int8 (mean difference from fp32 %.4f on %d frames)", diff, len(feeds))
    write_cached(path, generator.onnx)
    return generator
