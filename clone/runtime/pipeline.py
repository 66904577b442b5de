"""Run the stages of a frame loop side by side in threads, so the slowest stage alone sets the rate.

``clone drive`` draws pose maps, runs the generator and feeds the H.264 encoder. The generator depends on
its own previous frame, so frames cannot be batched; they can be pipelined: while the generator makes frame
``t``, a thread draws the pose maps of later frames (:func:`prefetch`) and another hands finished frames
to the encoder (:class:`BackgroundSink`). Torch, OpenCV and pipe writes release the GIL, so the threads
really overlap. Queues are small (memory stays bounded), items keep their order, and an error in any
stage ends the loop with that error; nothing is left running.
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Callable, Iterable, Iterator
from typing import Generic, TypeVar

T = TypeVar("T")

_POLL_S = 0.1  # how often a blocked thread checks whether the other side gave up
_DONE = object()  # end of a stream


class _Failed:
    """A worker's exception, carried through the queue to the thread that reads it."""

    def __init__(self, error: BaseException) -> None:
        self.error = error


def _put(q: queue.Queue, item: object, stop: threading.Event) -> bool:
    """Put ``item`` unless ``stop`` is set first; whether it was put."""
    while not stop.is_set():
        try:
            q.put(item, timeout=_POLL_S)
            return True
        except queue.Full:
            continue
    return False


def prefetch(items: Iterable[T], depth: int = 2, name: str = "prefetch") -> Iterator[T]:
    """The items of ``items``, produced by a background thread up to ``depth`` items ahead.

    An exception raised while producing an item is raised here, where that item would have come. Closing
    the returned generator early (``break``, an error in the caller, garbage collection) stops the thread.

    Args:
        items: any iterable; it is iterated in the background thread only.
        depth: most items produced but not yet taken (>= 1).
        name: the thread's name (for debugging).

    Yields:
        The items, in order.
    """
    if depth < 1:
        raise ValueError(f"prefetch depth must be >= 1, got {depth}")
    q: queue.Queue = queue.Queue(maxsize=depth)
    stop = threading.Event()

    def work() -> None:
        try:
            for item in items:
                if not _put(q, item, stop):
                    return
            _put(q, _DONE, stop)
        except BaseException as err:  # noqa: BLE001 - handed to the consumer, which raises it
            _put(q, _Failed(err), stop)

    thread = threading.Thread(target=work, name=name, daemon=True)
    thread.start()
    try:
        while True:
            item = q.get()
            if item is _DONE:
                return
            if isinstance(item, _Failed):
                raise item.error
            yield item
    finally:
        stop.set()
        thread.join()


class BackgroundSink(Generic[T]):
    """Hand items to ``consume`` in a background thread, in order, at most ``depth`` waiting.

    Use as a context manager: leaving the block normally waits until every item was consumed and raises
    the consumer's error, if any; leaving it with an error drops what is still waiting and stops the thread.
    :meth:`put` raises the consumer's error as soon as it is known, so the producer stops early too.

    Args:
        consume: called with each item in the background thread (e.g. ``VideoWriter.write``).
        depth: most items put but not yet consumed (>= 1).
        name: the thread's name.
    """

    def __init__(self, consume: Callable[[T], None], depth: int = 4, name: str = "sink") -> None:
        if depth < 1:
            raise ValueError(f"sink depth must be >= 1, got {depth}")
        self._consume = consume
        self._queue: queue.Queue = queue.Queue(maxsize=depth)
        self._stop = threading.Event()
        self._error: BaseException | None = None
        self._thread = threading.Thread(target=self._work, name=name, daemon=True)

    def __enter__(self) -> BackgroundSink[T]:
        self._thread.start()
        return self

    def _work(self) -> None:
        while True:
            try:
                item = self._queue.get(timeout=_POLL_S)
            except queue.Empty:
                if self._stop.is_set():
                    return
                continue
            if item is _DONE or self._stop.is_set():  # the producer failed: drop what still waits
                return
            try:
                self._consume(item)
            except BaseException as err:  # noqa: BLE001 - raised in the producer's thread
                self._error = err
                self._stop.set()
                return

    def put(self, item: T) -> None:
        """Queue ``item`` (blocks while ``depth`` items wait); raises the consumer's error if it failed."""
        if self._error is not None or not _put(self._queue, item, self._stop):
            self._raise()

    def _raise(self) -> None:
        if self._error is not None:
            raise self._error
        raise RuntimeError("BackgroundSink.put after the sink stopped")

    def __exit__(self, exc_type: type[BaseException] | None, *_: object) -> None:
        if exc_type is None:
            _put(self._queue, _DONE, self._stop)
        else:
            self._stop.set()  # the producer failed: what still waits is not consumed
        self._thread.join()
        if exc_type is None and self._error is not None:
            raise self._error
