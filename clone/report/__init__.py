"""The report of a `clone report` run: one folder with a self-contained page, its video, plots and numbers.

Layout of a report folder (all links in the page are relative, so the folder can be moved or zipped)::

    report.html          the page (inline CSS, no scripts, no network)
    side_by_side.mp4     driver | global scaling | retargeted | ground truth (written by the caller)
    metrics.json         per method: summary numbers, per-frame curves, details
    curves.png           per-frame curves of every measure, one line per method
    summary.png          one bar chart per summary measure
    still_<frame>.png    a few frames side by side with the skeletons drawn over them
    .clone2d-report      marker: this folder was made by a report and may be replaced with --overwrite

The folder is built in a temporary sibling and renamed into place, so a failed run leaves nothing behind.
An existing folder is replaced only when it carries the marker and the caller passes ``overwrite``.

Modules, one job each: ``results`` (what is compared, file names, colours, number formatting), ``folder``
(the output folder rules), ``panels`` (images and stills), ``plots`` (matplotlib figures), ``document``
(metrics.json), ``page`` (report.html), ``write`` (a report from measured results), ``ground_truth``
(reading and checking it), ``run`` (``make_report``: `clone report` end to end) and ``overview`` (one page over
several report folders, with a summary table across them: what `clone demo` writes above its pairs).
"""

from clone.report.document import METRICS_FORMAT, METRICS_VERSION, metrics_document
from clone.report.folder import MARKER, check_report_dir, report_dir
from clone.report.ground_truth import open_gt_frames, read_gt_poses
from clone.report.overview import PairSection, read_section, render_overview, write_overview
from clone.report.page import render_page
from clone.report.panels import caption_height, overlay, pose_panel, side_by_side, still_indices, write_stills
from clone.report.plots import plot_curves, plot_summary
from clone.report.results import (
    CURVES,
    METRICS_FILE,
    PAGE,
    SUMMARY,
    VIDEO,
    DriverInfo,
    GroundTruth,
    MethodResult,
    best_methods,
    format_value,
)
from clone.report.run import REPORT_METHODS, ReportRun, make_report
from clone.report.write import write_report, write_report_files

__all__ = [
    "CURVES",
    "MARKER",
    "METRICS_FILE",
    "METRICS_FORMAT",
    "METRICS_VERSION",
    "PAGE",
    "REPORT_METHODS",
    "SUMMARY",
    "VIDEO",
    "DriverInfo",
    "GroundTruth",
    "MethodResult",
    "PairSection",
    "ReportRun",
    "best_methods",
    "caption_height",
    "check_report_dir",
    "format_value",
    "make_report",
    "metrics_document",
    "open_gt_frames",
    "overlay",
    "plot_curves",
    "plot_summary",
    "pose_panel",
    "read_gt_poses",
    "read_section",
    "render_overview",
    "render_page",
    "report_dir",
    "side_by_side",
    "still_indices",
    "write_overview",
    "write_report",
    "write_report_files",
    "write_stills",
]
