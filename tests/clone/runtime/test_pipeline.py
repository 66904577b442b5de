"""clone.runtime.pipeline: order, bounded queues, errors from either side, and no thread left behind."""

from __future__ import annotations

import threading
import time

import pytest

from clone.runtime.pipeline import BackgroundSink, prefetch


def _threads(name: str) -> list[threading.Thread]:
    return [t for t in threading.enumerate() if t.name == name]


def test_prefetch_keeps_order_and_stays_bounded():
    produced = []

    def items():
        for i in range(50):
            produced.append(i)
            yield i

    stream = prefetch(items(), depth=3, name="t-prefetch-order")
    assert next(stream) == 0
    time.sleep(0.2)  # the producer runs ahead, but not further than the queue allows
    assert len(produced) <= 1 + 3 + 1  # taken + queued + one waiting to be put
    assert [0, *stream] == list(range(50))
    assert not _threads("t-prefetch-order")


def test_prefetch_raises_the_producers_error_where_its_item_would_come():
    def items():
        yield 1
        yield 2
        raise KeyError("boom")

    stream = prefetch(items(), name="t-prefetch-error")
    assert next(stream) == 1 and next(stream) == 2
    with pytest.raises(KeyError, match="boom"):
        next(stream)
    assert not _threads("t-prefetch-error")


def test_closing_a_prefetch_early_stops_its_thread():
    def endless():
        i = 0
        while True:
            yield i
            i += 1

    stream = prefetch(endless(), depth=2, name="t-prefetch-close")
    assert [next(stream) for _ in range(5)] == list(range(5))
    stream.close()
    assert not _threads("t-prefetch-close")


def test_sink_consumes_everything_in_order_before_the_block_ends():
    seen = []

    def slow(item: int) -> None:
        time.sleep(0.001)
        seen.append(item)

    with BackgroundSink(slow, depth=2, name="t-sink-order") as sink:
        for i in range(40):
            sink.put(i)
    assert seen == list(range(40))
    assert not _threads("t-sink-order")


def test_sink_error_reaches_the_producer():
    def fails_at_3(item: int) -> None:
        if item == 3:
            raise OSError("disk full")

    with pytest.raises(OSError, match="disk full"), BackgroundSink(fails_at_3, depth=1, name="t-sink-error") as sink:
        for i in range(1000):
            sink.put(i)
    assert not _threads("t-sink-error")


def test_producer_error_stops_the_sink_without_consuming_the_rest():
    seen = []
    gate = threading.Event()

    def blocked(item: int) -> None:
        gate.wait(5)
        seen.append(item)

    opener = threading.Timer(0.3, gate.set)  # a consumer busy with item 0 finishes it after the producer failed
    opener.start()
    with pytest.raises(ValueError, match="producer"), BackgroundSink(blocked, depth=4, name="t-sink-abort") as sink:
        for i in range(4):
            sink.put(i)
        raise ValueError("producer")
    opener.join()
    assert not _threads("t-sink-abort")
    assert len(seen) <= 1  # at most the item being consumed when the producer failed; the rest was dropped


@pytest.mark.parametrize("depth", [0, -1])
def test_bad_depth(depth):
    with pytest.raises(ValueError):
        next(prefetch([1], depth=depth))
    with pytest.raises(ValueError):
        BackgroundSink(print, depth=depth)
