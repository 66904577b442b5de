"""Poses straight from a video, extracted once and cached by the video's content.

Every command that reads poses takes a video file too (``clone train-ref REF.mp4``, ``clone drive DRIVER.mp4``,
``clone report``, ``clone pose info``): :func:`video_track_path` runs MediaPipe on it (:mod:`pose_io.extract`) and
keeps the track, in MediaPipe's 33 points (face, hands and feet included), as an ``.npz`` under
``~/.cache/clone2d/poses/`` (``CLONE2D_CACHE`` moves the root), named by a SHA-256 of the video's bytes and the
extractor's settings: a second run, of any command, on the same video does not extract again, and a renamed or
copied video is found too. The entries used least recently go when the folder passes :data:`MAX_CACHE_BYTES`.

A video with nobody in it ends as an :class:`InputError`; nothing half-written enters the cache (the entry is
written to a temporary sibling and renamed), so an interrupted extraction leaves nothing behind.
"""

from __future__ import annotations

import hashlib
import logging
import os
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import asdict
from pathlib import Path

from pose_io.atomic import cache_root, mark_used, prune_lru
from pose_io.errors import InputError

log = logging.getLogger(__name__)

VIDEO_SUFFIXES = (".mp4", ".m4v", ".mov", ".avi", ".mkv", ".webm", ".mpg", ".mpeg", ".wmv", ".flv", ".3gp",
                  ".ts", ".mts", ".m2ts", ".ogv",
                  # sound files: read as a video they end in one clear error (no video stream) instead of an
                  # unknown pose format
                  ".m4a", ".mp3", ".wav", ".aac", ".flac", ".ogg", ".opus")
# What goes into every cache key besides the content: bump when extraction changes what it writes.
EXTRACTOR_VERSION = "mediapipe-pose-0.10.14/1"
# A track costs 33 x 3 float32 per frame: 43 MB for an hour at 30 fps; 512 MB keeps a dozen such hours.
MAX_CACHE_BYTES = 512 * 2**20

# (frames done, frames in all, seconds so far) while a video is being extracted; set by the command line.
ExtractProgress = Callable[[int, int, float], None]
_progress: ContextVar[ExtractProgress | None] = ContextVar("extract_progress", default=None)


def is_video(path: str | os.PathLike) -> bool:
    """Whether ``path`` is a file with a video suffix (what the pose readers hand to extraction)."""
    path = Path(path)
    return path.suffix.lower() in VIDEO_SUFFIXES and not path.is_dir()


def pose_cache_dir() -> Path:
    """Where extracted tracks are kept: ``<cache root>/poses``."""
    return cache_root() / "poses"


def content_key(video: Path, settings: str) -> str:
    """SHA-256 of the video's bytes, the extractor version and ``settings`` (hex, 64 characters)."""
    digest = hashlib.sha256()
    digest.update(f"{EXTRACTOR_VERSION}\n{settings}\n".encode())
    try:
        with open(video, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                digest.update(block)
    except OSError as exc:
        raise InputError(f"{video}: cannot read ({exc.strerror or exc})") from None
    return digest.hexdigest()


@contextmanager
def extraction_progress(callback: ExtractProgress) -> Iterator[None]:
    """Within the block, extractions report ``callback(done, total, seconds)`` after each frame."""
    token = _progress.set(callback)
    try:
        yield
    finally:
        _progress.reset(token)


def video_track_path(video: str | os.PathLike, cache_dir: Path | None = None) -> Path:
    """The ``.npz`` of ``video``'s mediapipe33 track, extracted now unless the cache has it.

    Raises:
        InputError: the video cannot be read, MediaPipe is missing, or nobody is in any frame.
    """
    import time

    from pose_io.extract import ExtractConfig, extract_track, load_mediapipe_pose
    from pose_io.video import read_frames
    from pose_io.writers import write_track

    video = Path(video)
    if not video.is_file():
        raise InputError(f"{video}: does not exist")
    config = ExtractConfig()
    folder = cache_dir or pose_cache_dir()
    path = folder / f"{content_key(video, repr(asdict(config)))}.npz"
    if path.is_file():
        try:
            from pose_io.read_arrays import read_npz

            read_npz(path)
            mark_used(path)
            log.info("%s: poses from the cache (%s)", video, path)
            return path
        except InputError as exc:
            log.warning("the cached poses %s do not read back (%s); extracting again", path, exc)
    load_mediapipe_pose()  # the install line before the video is opened
    frames = read_frames(video)
    total = frames.num_frames
    report = _progress.get()
    t0 = time.perf_counter()

    def on_frame(t: int, _frame: object) -> None:
        if report is not None:
            report(t + 1, total, time.perf_counter() - t0)

    track = extract_track(frames, config, on_frame=on_frame)
    found = int((~track.missing).any(axis=1).sum())
    if found == 0:
        raise InputError(f"{video}: MediaPipe found no person in any of {track.num_frames} frames")
    log.info("%s: person found in %d of %d frames", video, found, track.num_frames)
    try:
        folder.mkdir(parents=True, exist_ok=True)
        write_track(track, path, overwrite=True)
    except OSError as exc:
        raise InputError(f"cannot keep the poses of {video} in the cache {folder} ({exc.strerror or exc}); "
                         "set CLONE2D_CACHE to a writable folder, or extract them with `clone pose extract`"
                         ) from None
    prune_lru(folder, "*.npz", keep=path, max_bytes=MAX_CACHE_BYTES, what="pose cache")
    return path
