"""Which method is better at a measure, and how the report prints a value."""

from __future__ import annotations

from clone import metrics
from clone.report.results import MethodResult, best_methods, format_value, method_colors, summary_keys
from tests.clone.report.helpers import make_methods


def test_best_methods_and_formatting():
    methods, _, _ = make_methods(with_frames=False)
    assert best_methods(methods, "root_rmse_pct") == {"retarget"}  # the other one is misplaced by 3 px
    assert best_methods(methods, "pck_0.1") == set()  # a tie (the same MidHip-aligned pose) highlights nobody
    differ = {n: MethodResult(m.label, m.poses, metrics.Scores(summary={"contact_share": i / 2}))
              for i, (n, m) in enumerate(methods.items())}  # fmt: skip
    assert best_methods(differ, "contact_share") == set()  # a description, not a quality
    assert format_value(float("inf")) == "∞" and format_value(float("nan")) == "–"
    assert format_value(0.0123, 1000.0) == "12.3"


def test_colors_and_summary_keys():
    methods, _, _ = make_methods(with_frames=False)
    colors = method_colors(methods)
    assert list(colors) == list(methods) and len(set(colors.values())) == len(methods)
    keys = summary_keys(methods)
    assert keys == [k for k in metrics.METRICS if k in keys]  # METRICS order
    assert "pose_mse" in keys and "ssim" not in keys  # no frames were scored
    assert format_value(None) == "–" and format_value(-float("inf")) == "−∞"
    assert format_value(123.456) == "123.5" and format_value(0.0) == "0" and format_value(1e-4) == "1.00e-04"
