"""The one progress bar of the command line: a transient rich bar on stderr, updated by a plain callback.

    with progress_bar("drive") as bar:
        run_drive(..., progress=bar)            # bar(done, total): completed / total (None: not known yet)
    with progress_bar("train-ref", count=False, elapsed=True, enabled=is_main) as bar:
        bar(step, total, text="l1 0.12")        # text: a note after the bar; label: replaces the name

The bar leaves nothing on the terminal when it ends (an error ends as its one ``error:`` line), and nothing
from rich is imported before a command runs (``clone --help`` stays light).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING

from clone.cli.common import console

if TYPE_CHECKING:
    from rich.progress import Progress, TaskID


class Bar:
    """One bar's update callback: ``bar(done, total=None, text=None, label=None)``."""

    def __init__(self, progress: Progress, task: TaskID) -> None:
        self._progress, self._task = progress, task

    def __call__(self, done: float, total: float | None = None, text: str | None = None,
                 label: str | None = None) -> None:
        fields = {} if text is None else {"text": text}
        if label is not None:
            fields["description"] = label
        self._progress.update(self._task, completed=done, total=total or None, **fields)


@contextmanager
def progress_bar(label: str, *, count: bool = True, elapsed: bool = False, remaining: bool = True,
                 enabled: bool = True) -> Iterator[Bar]:
    """A transient progress bar named ``label``; yields its :class:`Bar`.

    Args:
        label: the bar's name (shown before it).
        count: show ``done/total``.
        elapsed: show the time since the start.
        remaining: show the estimated time left.
        enabled: False draws nothing (e.g. on every process of a distributed run but the first).
    """
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    columns = [TextColumn("[bold]{task.description}"), BarColumn()]
    columns += [MofNCompleteColumn()] if count else []
    columns += [TextColumn("{task.fields[text]}")]
    columns += [TimeElapsedColumn()] if elapsed else []
    columns += [TimeRemainingColumn()] if remaining else []
    with Progress(*columns, console=console, transient=True, disable=not enabled) as progress:
        yield Bar(progress, progress.add_task(label, total=None, text=""))


def extract_if_video(path: Path | None) -> None:
    """When ``path`` is a video, extract its poses now (into the cache, under a bar with frames/s), so the command's
    own reading finds them there; a pose file or folder is left alone."""
    from pose_io.video_poses import extraction_progress, is_video, video_track_path

    if path is None or not is_video(path) or not path.is_file():
        return
    with progress_bar(f"poses of {path.name}") as bar:

        def update(done: int, total: int, seconds: float) -> None:
            bar(done, total, text=f"{done / max(seconds, 1e-6):.1f} frames/s")

        with extraction_progress(update):
            video_track_path(path)


def training_progress(bar: Callable[..., None], before: dict[str, str]):
    """A ``StepProgress`` callback (:mod:`clone.train_ref.state`) drawing on ``bar``: steps with their losses,
    against the steps or the time budget; a phase named in ``before`` (e.g. ``{"reading": "reading frames"}``)
    as that text with its count."""

    def update(p) -> None:
        if p.phase in before:
            bar(p.step, p.total, text=f"{before[p.phase]} {p.step}/{p.total}")
            return
        losses = " ".join(f"{k} {v:.3f}" for k, v in p.losses.items())
        text = f"step {p.step}{'/' + str(p.total) if p.total else ''}  {losses}"
        if p.total is not None:
            bar(p.step, p.total, text=text)
        else:
            bar(p.elapsed, p.limit_s, text=text)

    return update
