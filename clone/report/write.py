"""Write a report from results already measured: metrics.json, the plots, the stills and the page.

``write_report_files`` fills a folder that is being built; ``write_report`` builds a whole report folder
atomically around it (``clone.report.folder``).
"""

from __future__ import annotations

import logging
import os
import shutil
from collections.abc import Mapping
from pathlib import Path

from clone.report.document import write_metrics
from clone.report.folder import report_dir
from clone.report.page import render_page
from clone.report.panels import write_stills
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
)
from pose_io.errors import InputError

log = logging.getLogger(__name__)


def write_report_files(
    stage: Path,
    methods: Mapping[str, MethodResult],
    driver: DriverInfo,
    gt: GroundTruth | None = None,
    video: str | None = VIDEO,
    still_height: int = 320,
) -> Path:
    """Write metrics.json, the plots, the stills and report.html into ``stage``.

    Args:
        stage: the (temporary) report folder.
        methods: name -> result, in column order.
        driver: what drove the reference.
        gt: the ground truth, if any.
        video: file name of the side-by-side video already in ``stage``, or None for no video.
        still_height: rows of each still's image part.

    Returns:
        Path of the page.

    Raises:
        ValueError: no methods, or a still of a frame past the driver's end.
        FileNotFoundError: ``video`` is not in ``stage``.
    """
    if not methods:
        raise ValueError("write_report: no methods to report")
    if video is not None and not (stage / video).is_file():
        raise FileNotFoundError(f"{stage / video}: the side-by-side video is missing")
    write_metrics(stage / METRICS_FILE, methods, driver, gt)
    has_curves = bool(plot_curves(stage / CURVES, methods, driver.poses.fps))
    has_summary = bool(plot_summary(stage / SUMMARY, methods))
    stills = write_stills(stage, methods, driver, gt, still_height)
    page = render_page(methods, driver, gt, video, stills, has_curves, has_summary)
    (stage / PAGE).write_text(page, encoding="utf-8")
    return stage / PAGE


def write_report(
    out_dir: str | os.PathLike,
    methods: Mapping[str, MethodResult],
    driver: DriverInfo,
    gt: GroundTruth | None = None,
    video: str | os.PathLike | None = None,
    overwrite: bool = False,
) -> Path:
    """Write a whole report folder atomically (see ``clone.report``).

    Args:
        out_dir: the report folder; an existing one must be a report and needs ``overwrite``.
        methods: name -> result, in column order.
        driver: what drove the reference.
        gt: the ground truth, if any.
        video: a finished side-by-side mp4, copied in as ``side_by_side.mp4``; None for a page without video.
        overwrite: replace an existing report folder.

    Returns:
        Path of report.html in its final place.

    Raises:
        InputError: ``video`` does not exist, or ``out_dir`` may not be written (nothing is written then).
    """
    out_dir = Path(out_dir)
    if video is not None and not Path(video).is_file():
        raise InputError(f"{video}: no such video")
    with report_dir(out_dir, overwrite) as stage:
        if video is not None:
            shutil.copyfile(video, stage / VIDEO)
        write_report_files(stage, methods, driver, gt, VIDEO if video is not None else None)
    log.info("report written to %s", out_dir)
    return out_dir / PAGE
