"""The report's plots: what they show, and that drawing them leaves matplotlib's global state alone."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import cv2

from clone import metrics
from clone.report.plots import plot_curves, plot_summary
from clone.report.results import MethodResult
from tests.clone.report.helpers import make_methods


def test_plots_list_their_measures(tmp_path):
    methods, info, _ = make_methods(frames=6)
    curves = plot_curves(tmp_path / "curves.png", methods, info.poses.fps)
    summary = plot_summary(tmp_path / "summary.png", methods)
    assert "psnr" in curves and "ssim" in summary  # frame scores included
    assert curves == [k for k in metrics.METRICS if k in curves]
    for name in ("curves.png", "summary.png"):
        image = cv2.imread(str(tmp_path / name))
        assert image is not None and image.shape[1] == 1100  # 11 inches at 100 dpi

    empty = {n: MethodResult(m.label, m.poses, metrics.Scores()) for n, m in methods.items()}
    assert plot_curves(tmp_path / "none.png", empty, 30.0) == []
    assert plot_summary(tmp_path / "none.png", empty) == []
    assert not (tmp_path / "none.png").exists()


def test_plots_leave_the_backend_alone(tmp_path):
    """A user's chosen backend survives a report, and pyplot (its global figure manager) is never loaded."""
    script = textwrap.dedent(f"""
        import sys
        import matplotlib
        matplotlib.use("svg")
        from clone.report.plots import plot_curves, plot_summary
        from tests.clone.report.helpers import make_methods
        methods, info, _ = make_methods(frames=4, with_frames=False)
        assert plot_curves({str(tmp_path / "c.png")!r}, methods, info.poses.fps)
        assert plot_summary({str(tmp_path / "s.png")!r}, methods)
        assert "matplotlib.pyplot" not in sys.modules, "pyplot was imported"
        assert matplotlib.get_backend() == "svg", matplotlib.get_backend()
    """)
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=False,
                          cwd=str(_repo_root()), timeout=300)  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    assert (tmp_path / "c.png").is_file() and (tmp_path / "s.png").is_file()


def _repo_root():
    from pathlib import Path

    return Path(__file__).resolve().parents[3]
