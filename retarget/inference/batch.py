"""Retargeting many pose files in one process: find them, name their outputs, run them through the network together.

    motions = [f.path for f in find_tracks(["clips/"], recursive=False, duplicates="refuse")]  # pose_io.folders
    outputs = batch_outputs(motions, Path("out"), "npz")     # out/<name>.npz, clashes refused
    retarget_files(retargeter, reference, motions, outputs, fmt="npz")

Every input is read and checked before the first output is written (a bad one raises :class:`InputError`
and nothing is written); then the clips' windows go through the network stacked together, and the outputs
are written, each atomically, ``chunk_frames`` frames of clips at a time (memory: the network inputs of all
clips, 120 bytes a frame, plus one chunk).
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path

from pose_io.errors import InputError
from pose_io.folders import is_openpose_folder
from pose_io.track import PoseTrack
from pose_io.writers import write_track
from retarget.inference.algorithm import RetargeterBase
from retarget.inference.config import PreparedMotion, ReferenceCodes

log = logging.getLogger(__name__)


def is_batch(inputs: Sequence[Path]) -> bool:
    """Whether the inputs name several clips: more than one path, or a folder that is not one OpenPose track."""
    return len(inputs) > 1 or (len(inputs) == 1 and inputs[0].is_dir() and not is_openpose_folder(inputs[0]))


def output_name(motion: Path, fmt: str) -> str:
    """The output file (``fmt`` npz or csv) or folder (openpose) named after an input: ``walk.csv`` -> ``walk.npz``."""
    stem = motion.name if motion.is_dir() else motion.stem
    return stem if fmt == "openpose" else f"{stem}.{fmt}"


def batch_outputs(motions: Sequence[Path], out_dir: Path, fmt: str) -> list[Path]:
    """``out_dir / output_name(m)`` for every input.

    Raises:
        InputError: two inputs that would write the same output.
    """
    outputs, by_name = [], {}
    for motion in motions:
        name = output_name(motion, fmt)
        if name in by_name:
            raise InputError(f"{motion} and {by_name[name]} would both write {out_dir / name}; rename one")
        by_name[name] = motion
        outputs.append(out_dir / name)
    return outputs


def retarget_files(
    retargeter: RetargeterBase,
    reference: ReferenceCodes,
    motions: Sequence[Path],
    outputs: Sequence[Path],
    *,
    read: Callable[[Path], PoseTrack],
    fmt: str,
    overwrite: bool = False,
    chunk_frames: int = 65_536,
    progress: Callable[[int, int], None] | None = None,
) -> int:
    """Retarget every motion file onto ``reference`` and write it to its output.

    Args:
        retargeter: either backend.
        reference: the reference's codes (:meth:`RetargeterBase.reference_codes`).
        motions: input files or OpenPose folders.
        outputs: one path per input.
        read: reads one input (e.g. :func:`pose_io.readers.read_track` with the user's options).
        fmt: output format, one of :data:`pose_io.writers.WRITERS`.
        overwrite: replace existing outputs.
        chunk_frames: frames retargeted before their outputs are written (at the network's rate).
        progress: called as ``progress(clips done, clips)`` while reading and while writing.

    Returns:
        Frames written.

    Raises:
        InputError: an input that cannot be read or retargeted (before anything is written).
    """
    total = len(motions)
    prepared: list[PreparedMotion] = []
    for k, path in enumerate(motions):
        prepared.append(retargeter.prepare_motion(read(path), str(path)))  # the track itself is dropped here
        if progress is not None:
            progress(k + 1, 2 * total)
    frames, done = 0, 0
    for chunk in _chunks(prepared, chunk_frames):
        for result, out in zip(retargeter.retarget_prepared(chunk, reference), outputs[done : done + len(chunk)]):
            write_track(result, out, fmt, overwrite=overwrite)
            frames += len(result)
        done += len(chunk)
        if progress is not None:
            progress(total + done, 2 * total)
    log.info("retargeted %d clips, %d frames", total, frames)
    return frames


def _chunks(items: list[PreparedMotion], frames: int) -> Iterator[list[PreparedMotion]]:
    """Consecutive runs of ``items`` of at most ``frames`` frames (a longer item alone), emptying ``items``."""
    items.reverse()  # popped from the end: each chunk is freed once written
    while items:
        chunk = [items.pop()]
        size = len(chunk[0])
        while items and size + len(items[-1]) <= frames:
            size += len(items[-1])
            chunk.append(items.pop())
        yield chunk
