"""`clone report` end to end: drive the reference model with every method, measure them, write the folder.

Every frame is generated once and used three ways (side-by-side video, frame scores against the ground
truth, still images), so memory does not grow with the driver's length.
"""

from __future__ import annotations

import contextlib
import importlib.util
import logging
import os
import time
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from clone.drive.coverage import Coverage, pose_coverage
from clone.metrics import FlickerMeter, FrameScorer, Scores, evaluate_track
from clone.model.canvas import image_to_canvas
from clone.report.folder import check_report_dir, report_dir
from clone.report.ground_truth import cut_gt_frames, open_gt_frames, read_gt_poses
from clone.report.panels import pose_panel, side_by_side, still_indices
from clone.report.results import PAGE, VIDEO, DriverInfo, GroundTruth, MethodResult
from clone.report.write import write_report_files
from pose_io.audio import resolve_audio
from pose_io.errors import InputError
from pose_io.layouts import BODY15
from pose_io.measures import reference_limb_lengths, skeleton_height
from pose_io.track import PoseTrack

if TYPE_CHECKING:
    from clone.metrics.consistency import ConsistencyMeter
    from clone.model.reference import ReferenceModel

log = logging.getLogger(__name__)

# The methods a report compares, in column order: drive method -> (column label, one-line description).
REPORT_METHODS: dict[str, tuple[str, str]] = {
    "global-scale": (
        "Global scaling",
        (
            "Everybody Dance Now's global normalisation: the driver scaled and moved per frame from its feet "
            "range onto the reference's, so it keeps the driver's own proportions."
        ),
    ),
    "retarget": (
        "Retargeted",
        (
            "the retargeting network (Aberman et al. 2019): the driver's motion code decoded with the "
            "reference's skeleton and view codes."
        ),
    ),
}


@dataclass(frozen=True)
class ReportRun:
    """What `clone report` wrote.

    Attributes:
        page: the report page.
        frames: frames compared.
        summary: method -> its summary numbers.
        seconds: wall time of the run.
        coverage_line: the retargeted drive's coverage line (:meth:`clone.drive.coverage.Coverage.line`), or None.
    """

    page: Path
    frames: int
    summary: dict[str, dict[str, float]]
    seconds: float
    coverage_line: str | None = None


@dataclass
class _Kept:
    """What the video pass keeps of the frames it generates: frame scores and the still frames.

    Attributes:
        at: the still frame indices.
        scorers: method -> its frame scores against the ground-truth frames (empty without them).
        stills: method -> frame index -> [S, S, 3] uint8 RGB generated frame.
        gt_stills: frame index -> [S, S, 3] uint8 RGB true frame cut to the canvas.
        bodies: method -> [T, 15, 2] its driven body15 poses in canvas pixels (the boxes flicker is measured in,
            the poses consistency is measured against).
        truth_body: [T, 15, 2] the true poses in canvas pixels, or None.
        flicker: method -> its flicker in the person's box (:class:`clone.metrics.FlickerMeter`).
        truth_flicker: the true frames' flicker in the true pose's box.
        consistency: method -> its pose consistency meter (empty when not measured).
    """

    at: set[int]
    scorers: dict[str, FrameScorer]
    stills: dict[str, dict[int, np.ndarray]]
    gt_stills: dict[int, np.ndarray] = field(default_factory=dict)
    bodies: dict[str, np.ndarray] = field(default_factory=dict)
    truth_body: np.ndarray | None = None
    flicker: dict[str, FlickerMeter] = field(default_factory=dict)
    truth_flicker: FlickerMeter = field(default_factory=FlickerMeter)
    consistency: dict[str, ConsistencyMeter] = field(default_factory=dict)

    def add(self, t: int, frames: Mapping[str, np.ndarray], true_frame: np.ndarray | None) -> None:
        """Score frame ``t`` of every method against the true frame and on its own (flicker, pose consistency
        when measured), and keep it when it is a still."""
        for m, frame in frames.items():
            body = self.bodies[m][t] if m in self.bodies else None
            self.flicker.setdefault(m, FlickerMeter()).add(frame, body)
            if m in self.consistency and body is not None:
                self.consistency[m].add(frame, body)
        if true_frame is not None:
            has_truth = self.truth_body is not None and t < len(self.truth_body)
            self.truth_flicker.add(true_frame, self.truth_body[t] if has_truth else None)
            for m, frame in frames.items():
                self.scorers[m].add(frame, true_frame)
        if t in self.at:
            for m, frame in frames.items():
                self.stills[m][t] = frame
            if true_frame is not None:
                self.gt_stills[t] = true_frame


def _panel_height(canvas_size: int) -> int:
    """Rows of each video panel: small canvases are scaled up so captions stay legible."""
    return min(max(canvas_size, 256), 512)


def _write_video(
    path: Path,
    model: ReferenceModel,
    driver: PoseTrack,
    driven: Mapping[str, PoseTrack],
    truth_frames: Iterator[np.ndarray] | None,
    kept: _Kept,
    device: str,
    progress: Callable[[int, int], None] | None,
    audio: Path | None = None,
) -> None:
    """Generate every method's frames and write driver | methods | ground truth side by side to ``path``
    (with the sound of ``audio`` when given).

    Args:
        path: the mp4 to write.
        model: the reference model.
        driver: the driver's poses.
        driven: method -> the driver's poses moved onto the reference (``clone.drive.poses.drive_poses``).
        truth_frames: the true frames cut to the canvas (``cut_gt_frames``), or None.
        kept: receives the frame scores and stills.
        device: where the generator runs.
        progress: called with (frames done, total) after every frame.
    """
    from clone.runtime.generate import generate_frames
    from pose_io.video_out import VideoWriter

    height = _panel_height(model.canvas.size)
    labels = ["Driver", *(REPORT_METHODS[m][0] for m in driven)]
    labels += ["Ground truth"] if truth_frames is not None else []
    with contextlib.ExitStack() as open_, VideoWriter(path, fps=driver.fps, audio=audio) as video:
        # every stream closed when the video ends or fails (each holds its drawing and face-pass threads)
        streams = [open_.enter_context(contextlib.closing(generate_frames(model, track, device)))
                   for track in driven.values()]
        for meter in kept.consistency.values():
            open_.enter_context(meter)
        for t, outputs in enumerate(zip(*streams)):
            frames = dict(zip(driven, (frame for _pose_map, frame in outputs)))  # [S, S, 3] uint8 each
            true_frame = None if truth_frames is None else next(truth_frames)
            kept.add(t, frames, true_frame)
            panels = [
                pose_panel(driver.joints[t], driver.layout, driver.image_size, height),
                *frames.values(),
            ]
            panels += [] if true_frame is None else [true_frame]
            video.write(side_by_side(panels, labels, height))
            if progress is not None:
                progress(t + 1, driver.num_frames)


def _method_results(
    driven: Mapping[str, PoseTrack],
    model: ReferenceModel,
    reference: tuple[np.ndarray, float],
    truth: PoseTrack | None,
    kept: _Kept,
    shares: Mapping[str, float],
    coverage: dict[str, Coverage] | None = None,
) -> dict[str, MethodResult]:
    """Every method measured, with its stills and its poses in the stills' (canvas) pixels.

    Args:
        driven: method -> its driven poses.
        model: the reference model.
        reference: the reference's [L] limb lengths and its height in pixels (``pose_io.measures``).
        truth: the ground-truth poses, or None.
        kept: the frame scores and stills of the video pass.
        shares: method -> share of frames moved onto the reference's stage (``clone.drive.stage.StageFit.share``);
            methods the stage was not applied to are missing.
        coverage: receives method -> its pose coverage (:mod:`clone.drive.coverage`).
    """
    at = sorted(kept.at)
    methods = {}
    coverage = {} if coverage is None else coverage
    truth_flicker = kept.truth_flicker.value()
    for m, detailed in driven.items():
        track = detailed.to_layout(BODY15.name)  # measured and drawn as the network's joints
        scores = evaluate_track(track, *reference, truth)
        if m in kept.scorers:
            scores = scores.merged(kept.scorers[m].scores())
        if m in kept.flicker:
            flicker = kept.flicker[m]
            summary = {"flicker": flicker.value()}
            if np.isfinite(truth_flicker) and truth_flicker > 0:
                summary["flicker_ratio"] = flicker.value() / truth_flicker
            scores = scores.merged(Scores(per_frame={"flicker": flicker.per_frame()}, summary=summary))
        if m in kept.consistency:
            found = kept.consistency[m].scores()
            scores = scores.merged(Scores(summary={"consistency_pck": found["pck_0.1"],
                                                   "consistency_median_pct": found["median_error_pct"]}))
        if m in shares:
            scores = scores.merged(Scores(summary={"stage_share": float(shares[m])}))
        cover = pose_coverage(track, model.reference_track)
        scores = scores.merged(Scores(
            per_frame={"novelty_pct": 100.0 * cover.distance.astype(np.float64)},
            summary={"novelty_pct": 100.0 * float(np.nanmean(cover.distance)) if np.isfinite(cover.distance).any()
                     else float("nan"), "uncovered_share": cover.share},
            details={"uncovered_parts": dict(cover.parts)}))
        coverage[m] = cover
        still_poses = dict(zip(at, image_to_canvas(track.joints[at], model.canvas)))  # t -> [J, 2] canvas px
        label, description = REPORT_METHODS[m]
        methods[m] = MethodResult(label, track, scores, kept.stills[m], still_poses, description)
    return methods


def _ground_truth_info(
    gt_poses: str | os.PathLike | None,
    gt_frames: str | os.PathLike | None,
    truth_canvas: np.ndarray | None,
    gt_stills: dict[int, np.ndarray],
) -> GroundTruth | None:
    """The ground truth as the report shows it, or None when neither its poses nor its frames were given.

    Args:
        gt_poses: where its poses were read from, or None.
        gt_frames: where its frames were read from, or None.
        truth_canvas: [T, J, 2] its poses in canvas pixels, or None.
        gt_stills: frame index -> [S, S, 3] uint8 RGB true frame cut to the canvas.
    """
    if gt_poses is None and gt_frames is None:
        return None
    still_poses = {} if truth_canvas is None else {t: truth_canvas[t] for t in gt_stills}
    return GroundTruth(
        None if gt_poses is None else str(gt_poses),
        None if gt_frames is None else str(gt_frames),
        gt_stills,
        still_poses,
    )


def _driver_baseline(driver: PoseTrack) -> Scores | None:
    """The driver measured against its own proportions and height (None when it has no full skeleton)."""
    try:
        return evaluate_track(driver, reference_limb_lengths(driver.joints, driver.layout),
                              skeleton_height(driver.joints, driver.layout))  # fmt: skip
    except InputError as exc:
        log.warning("no driver baseline: %s", exc)
        return None


def make_report(
    driver_path: str | os.PathLike,
    out_dir: str | os.PathLike,
    *,
    model_path: str | os.PathLike,
    gt_poses: str | os.PathLike | None = None,
    gt_frames: str | os.PathLike | None = None,
    overwrite: bool = False,
    device: str = "cpu",
    weights: str | os.PathLike | None = None,
    max_gap: int = 5,
    progress: Callable[[int, int], None] | None = None,
    stage: str = "frame",
    refine_steps: int | None = None,
    audio: str | os.PathLike | None = "auto",
    consistency: bool | None = None,
) -> ReportRun:
    """Drive the reference model with both methods, measure them and write the report folder.

    Args:
        driver_path: the driver's poses (any format ``pose_io`` reads).
        out_dir: the report folder (see ``clone.report.folder`` for the overwrite rules).
        model_path: the reference model from ``clone train-ref``.
        gt_poses: poses of the reference really performing the driver's motion, frame for frame.
        gt_frames: frames (video or image folder) of the same, the reference's frame size.
        overwrite: replace an existing report folder.
        device: where the networks run.
        weights: retargeting weights (default: see ``clone.drive.poses.retargeting_weights``).
        max_gap: fill driver gaps of at most this many frames.
        progress: called with (frames done, total) after every frame.
        stage: ``frame``, ``reference`` or ``raw`` (see ``clone.drive.poses.drive_poses``).
        refine_steps: motion-code refinement steps of the retargeted row (None: inference's default; 0: none).
        audio: the video's sound: ``auto`` the driver's when it is a video with sound, ``none`` silent, else a
            file (see :func:`pose_io.audio.resolve_audio`).
        consistency: measure pose consistency, MediaPipe run on every generated frame against the poses it was
            made from (:mod:`clone.metrics.consistency`; about 20 ms a frame and method on a CPU); None: when
            MediaPipe is installed (the ``extract`` extra).

    Returns:
        Where the page is and the summary numbers.
    """
    from clone.drive.poses import drive_poses, read_driver  # torch loads only when a report is made
    from clone.model.reference import load_reference_model

    t0 = time.perf_counter()
    out_dir = Path(out_dir)
    check_report_dir(out_dir, overwrite)  # before any slow work
    sound = resolve_audio(audio, driver_path)
    model = load_reference_model(model_path)
    canvas = model.canvas
    driver = read_driver(driver_path, max_gap, layout=model.pose_layout)
    total = driver.num_frames
    truth = None if gt_poses is None else read_gt_poses(gt_poses, total, canvas.image_size)
    truth_frames = None if gt_frames is None else open_gt_frames(gt_frames, total, canvas.image_size)
    ref = model.reference_track
    reference = (reference_limb_lengths(ref.joints, ref.layout), skeleton_height(ref.joints, ref.layout))
    moved = {m: drive_poses(driver, model, m, weights, device, stage, refine_steps=refine_steps) for m in REPORT_METHODS}
    driven = {m: track for m, (track, _fit) in moved.items()}
    shares = {m: fit.share for m, (_track, fit) in moved.items() if fit is not None}
    truth_canvas = None if truth is None else image_to_canvas(truth.joints, canvas)  # [T, J, 2] canvas px
    scorers = {m: FrameScorer(truth_canvas) for m in driven} if truth_frames is not None else {}
    kept = _Kept(set(still_indices(total)), scorers, {m: {} for m in driven})
    kept.bodies = {m: image_to_canvas(t.to_layout(BODY15.name).joints, canvas) for m, t in driven.items()}
    if truth_canvas is not None and truth is not None:
        kept.truth_body = image_to_canvas(truth.to_layout(BODY15.name).joints, canvas)
    if consistency is None:
        consistency = importlib.util.find_spec("mediapipe") is not None
        if not consistency:
            log.info("MediaPipe is not installed: no pose consistency in the report")
    if consistency:
        from clone.metrics.consistency import ConsistencyMeter

        kept.consistency = {m: ConsistencyMeter() for m in driven}

    with report_dir(out_dir, overwrite) as folder:
        cut = None if truth_frames is None else cut_gt_frames(truth_frames, gt_frames, total, canvas)
        _write_video(folder / VIDEO, model, driver, driven, cut, kept, device, progress, sound)
        coverage: dict[str, Coverage] = {}
        methods = _method_results(driven, model, reference, truth, kept, shares, coverage)
        gt_info = _ground_truth_info(gt_poses, gt_frames, truth_canvas, kept.gt_stills)
        info = DriverInfo(driver, str(driver_path), str(model_path), _driver_baseline(driver))
        write_report_files(folder, methods, info, gt_info, VIDEO)
    summary = {m: dict(r.scores.summary) for m, r in methods.items()}
    line = coverage["retarget"].line() if "retarget" in coverage else None
    return ReportRun(out_dir / PAGE, total, summary, time.perf_counter() - t0, line)
