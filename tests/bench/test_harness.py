"""bench.harness: how timings are taken and how a row's ratio to its baseline is computed (no timing asserts)."""

from __future__ import annotations

import pytest

from bench.harness import Timing, load_average, peak_rss_mb, row, rss_mb, time_call


def test_time_call_warms_up_then_takes_one_sample_per_repeat():
    calls = []
    timing = time_call(lambda: calls.append(1), repeats=3, warmup=2)
    assert len(calls) == 5
    assert timing.repeats == 3 and len(timing.samples_s) == 3
    assert timing.median_s == sorted(timing.samples_s)[1]


def test_time_call_loops_short_calls_up_to_the_minimum_sample_time():
    calls = []
    timing = time_call(lambda: calls.append(1), repeats=2, warmup=0, min_time_s=0.01)
    assert len(calls) > 2  # an append takes far less than 10 ms: each sample looped
    assert all(s > 0 for s in timing.samples_s)


def test_rate_is_items_over_the_median():
    assert Timing(0.5, 3).rate(10) == 20.0
    assert Timing(0.0, 3).rate(10) == float("inf")


def test_row_speedup_is_better_than_one_when_better_than_the_baseline():
    rate = row("c", "ours", 30.0, "frames/s", 10.0, "plain")
    assert rate["speedup"] == 3.0 and rate["baseline"] == 10.0 and rate["baseline_variant"] == "plain"
    time = row("c", "ours", 2.0, "s", 3.0, "plain", higher_is_better=False)
    assert time["speedup"] == 1.5
    assert row("c", "ours", 1.0, "s", 3.0, higher_is_better=False)["speedup"] == 3.0
    assert row("c", "ours", 1.0, "frames/s", 3.0)["speedup"] == pytest.approx(0.333)  # rounded to 3 places


def test_row_without_a_usable_baseline_has_no_speedup():
    alone = row("c", "ours", 5, "MiB", peak=7)
    assert alone["baseline"] is None and alone["speedup"] is None and alone["baseline_variant"] is None
    assert alone["value"] == 5.0 and isinstance(alone["value"], float)
    assert alone["extra"] == {"peak": 7}
    assert row("c", "ours", 0.0, "frames/s", 3.0)["speedup"] is None
    assert row("c", "ours", 1.0, "frames/s", 0.0)["speedup"] is None


def test_load_average_and_memory_readings():
    la = load_average()
    assert la == [] or (len(la) == 3 and all(v >= 0 for v in la))
    assert 0 < rss_mb() <= peak_rss_mb() * 1.01
