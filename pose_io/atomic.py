"""Atomic outputs: write to a temporary sibling, then rename into place, so a failed run leaves nothing.

Used by every writer in the project. Nothing the user had is replaced unless they asked for it.
"""

from __future__ import annotations

import contextlib
import logging
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

from pose_io.errors import InputError

log = logging.getLogger(__name__)


def mark_used(path: Path) -> None:
    """Move a cache entry's (file or folder) modification time to now, so caches that drop the least recently
    used keep it; a read-only cache is still used as it is."""
    try:
        os.utime(path)
    except OSError as exc:
        log.debug("cannot mark %s as used (%s)", path, exc)


def cache_root() -> Path:
    """Where clone2d keeps its caches (motion worlds, int8 generators, extracted poses): ``$CLONE2D_CACHE``
    when set, else ``~/.cache/clone2d``."""
    root = os.environ.get("CLONE2D_CACHE")
    return Path(root) if root else Path.home() / ".cache" / "clone2d"


def prune_lru(folder: Path, pattern: str, keep: Path, max_bytes: int, what: str = "cache") -> list[Path]:
    """Delete the least recently used files matching ``pattern`` in ``folder`` until the rest fit in ``max_bytes``.

    ``keep`` (the entry just written) always stays, whatever its size; other files are left alone.

    Returns:
        The deleted files.
    """
    entries = []
    for file in folder.glob(pattern):
        try:
            stat = file.stat()
        except OSError:  # deleted meanwhile by another process
            continue
        entries.append((file == keep, stat.st_mtime_ns, stat.st_size, file))
    entries.sort(key=lambda e: (e[0], e[1]), reverse=True)  # the kept file, then the newest first
    total, deleted = 0, []
    for is_kept, _, size, file in entries:
        total += size
        if total > max_bytes and not is_kept:
            try:
                file.unlink()
                deleted.append(file)
            except OSError as exc:
                log.debug("cannot delete %s from the %s (%s)", file, what, exc)
    if deleted:
        log.info("%s: deleted %d least recently used entries to stay under %d MB", what, len(deleted),
                 max_bytes // 2**20)
    return deleted


def _umask(probe_dir: Path) -> int:
    """The process's file-creation mask, read without changing it (``os.umask`` can only be read by setting).

    Linux reports it in /proc; elsewhere a probe file created with mode 0666 in ``probe_dir`` shows it.
    """
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("Umask:"):
                return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    probe = probe_dir / f".umask-probe-{os.getpid()}-{id(probe_dir)}"
    fd = os.open(probe, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o666)
    try:
        return 0o666 & ~os.fstat(fd).st_mode & 0o777
    finally:
        os.close(fd)
        probe.unlink()


def nearest_existing(path: Path) -> Path:
    """``path`` or its nearest existing ancestor (the folder that the writer's ``mkdir(parents=True)`` starts in)."""
    path = Path(path).absolute()
    while not path.exists() and path != path.parent:
        path = path.parent
    return path


DISK_HINT = "use a smaller --size, fewer frames, or point TMPDIR at a bigger disk"


def check_free_space(folder: Path, nbytes: int, what: str, hint: str = DISK_HINT) -> None:
    """Raise InputError when ``folder``'s file system has less than ``nbytes`` (+10 %, +256 MiB) free.

    The one check before anything a user's option scales is allocated on disk; ``hint`` says what to change.
    """
    base = nearest_existing(Path(folder))
    free = shutil.disk_usage(base).free
    need = int(nbytes * 1.1) + (256 << 20)
    if free < need:
        raise InputError(f"{what} needs {need / 2**30:.1f} GiB in {base}, which has {free / 2**30:.1f} GiB free; "
                         f"{hint}")


def check_new_output(path: Path, overwrite: bool = False) -> None:
    """Raise InputError when ``path`` exists and ``overwrite`` is not set."""
    if path.exists() and not overwrite:
        raise InputError(f"{path}: already exists; choose another --out or pass --overwrite")


@contextlib.contextmanager
def atomic_file(path: str | os.PathLike, overwrite: bool = True) -> Iterator[Path]:
    """Yield a temporary path next to ``path``; on success it replaces ``path`` in one rename.

    Args:
        path: final file path.
        overwrite: if False and ``path`` exists, raise InputError before anything is written.
    """
    path = Path(path)
    check_new_output(path, overwrite)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp" + path.suffix, dir=path.parent)
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        # mkstemp makes the file private (0600); give it the permissions a plain open() would.
        os.chmod(tmp_path, 0o666 & ~_umask(tmp_path.parent))
        os.replace(tmp_path, path)
    finally:
        if tmp_path.exists():
            tmp_path.unlink()


@contextlib.contextmanager
def atomic_dir(path: str | os.PathLike, overwrite: bool = False) -> Iterator[Path]:
    """Yield a temporary folder next to ``path``; on success it becomes ``path``.

    With ``overwrite``, an existing ``path`` is replaced only after the new content is complete.
    """
    path = Path(path)
    check_new_output(path, overwrite)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent))
    try:
        yield tmp
        os.chmod(tmp, 0o777 & ~_umask(tmp.parent))
        if path.exists():
            old = path.with_name(f".{path.name}.old-{os.getpid()}")
            os.replace(path, old)
            os.replace(tmp, path)
            shutil.rmtree(old) if old.is_dir() else old.unlink()
        else:
            os.replace(tmp, path)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp)
