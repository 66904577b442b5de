"""The driver's poses moved onto a trained reference (the pose half of `clone drive`, also used by `clone report`,
`clone cartoon` and the demo's scoring).

1. Read the driver's track (any format ``pose_io`` reads), as body15, with short gaps filled (:func:`read_driver`).
2. Move it onto the reference (:func:`drive_poses`, ``--method``):
   - ``retarget``: the retargeting network, with the reference's skeleton and view codes stored in the model
     (recomputed from the stored reference track when other weights are given);
   - ``global-scale``: Everybody Dance Now's per-frame scale and translation between feet positions;
   - ``none``: the driver's pixel coordinates as they are, read as the reference's;
   then, for the first two, kept on the part of the frame the reference stood on (``--stage``, :mod:`clone.drive.stage`).

The video made from them is :mod:`clone.drive.run`.
"""

from __future__ import annotations

import logging
import os
from pathlib import Path

import numpy as np

from clone.choices import Method, StageMode
from clone.drive.stage import StageFit, fit_to_stage, start_on_reference
from clone.model.canvas import Canvas
from clone.model.reference import DETAIL_LAYOUT, LAYOUT, ReferenceModel, file_sha256
from pose_io.errors import InputError
from pose_io.track import PoseTrack
from retarget.baselines.global_scale import ScaleStats, apply_global_scale, scale_stats

log = logging.getLogger(__name__)

METHODS = tuple(m.value for m in Method)
STAGES = tuple(s.value for s in StageMode)


def read_driver(path: str | os.PathLike, max_gap: int = 5, layout: str = LAYOUT) -> PoseTrack:
    """The driver's track in ``layout`` (body15; body31 keeps the face, hands and feet it has), gaps of at most
    ``max_gap`` frames filled linearly."""
    from pose_io.readers import read_track

    return driver_track(read_track(path), max_gap, str(path), layout)


def driver_track(track: PoseTrack, max_gap: int = 5, name: str = "driver", layout: str = LAYOUT) -> PoseTrack:
    """A driver's track as `clone drive` uses it: in ``layout`` (body15 or body31), gaps of at most ``max_gap``
    frames filled linearly."""
    from pose_io.clean import fill_gaps

    track = track.to_layout(layout)
    if not (~track.missing).any():
        raise InputError(f"{name}: no visible joints in any frame")
    if max_gap > 0:
        track, _ = fill_gaps(track, max_gap)
    return track


def retargeting_weights(model: ReferenceModel, weights: str | os.PathLike | None) -> Path:
    """The weights file to retarget with: ``weights``; else the file the model's codes came from, when it is
    still there unchanged (a model trained with ``--weights X`` keeps using X); else the shipped weights."""
    from retarget.api import PACKAGED_WEIGHTS

    if weights is not None:
        return Path(weights)
    hint = Path(model.codes_weights_path) if model.codes_weights_path else None
    if hint is not None and hint.is_file() and file_sha256(hint) == model.codes_weights:
        log.info("retargeting with %s, the weights the model's codes came from", hint)
        return hint
    if PACKAGED_WEIGHTS.is_file():
        return PACKAGED_WEIGHTS
    if model.reference_codes is None:
        raise InputError("this reference model holds no retargeting codes (it was trained without retargeting "
                         "weights) and none are shipped; pass --weights FILE or use --method global-scale")
    raise InputError(f"the retargeting weights this model's codes came from ({model.codes_weights_path}) are "
                     "gone and none are shipped; pass --weights FILE or use --method global-scale")


def load_driving_retargeter(
    weights: str | os.PathLike | None, device: str = "cpu", refine_steps: int | None = None
):  # -> retarget.api.Retargeter | NumpyRetargeter
    """The retargeting network for driving: ``refine_steps`` motion-code refinement steps (None: inference's
    default); the numpy backend on the CPU when the weights have an up-to-date export (the shipped ones)."""
    from retarget.api import load_retargeter
    from retarget.inference.config import InferenceConfig

    config = None if refine_steps is None else InferenceConfig(refine_steps=refine_steps)
    return load_retargeter(weights, device=device, config=config, backend="auto")


def retarget_onto(
    driver: PoseTrack, model: ReferenceModel, weights: str | os.PathLike | None, device: str = "cpu",
    refine_steps: int | None = None,
) -> PoseTrack:
    """The driver's motion performed by the reference, in the reference's pixels (retargeting network).

    Uses the codes stored in the model when the same weights made them, pooled as today's inference pools
    them (``view_pool``); otherwise computes them from the reference track stored in the model. ``refine_steps``: motion-code refinement steps (None: inference's
    default; 0: the encoder's codes as they are, on the numpy backend when the weights have an export).
    """
    from retarget.api import ReferenceCodes

    path = retargeting_weights(model, weights)
    retargeter = load_driving_retargeter(path, device, refine_steps)
    stored = model.reference_codes
    # codes stored by the same weights and pooled as today (models trained before the view code's "facing"
    # pool store none: a reference who turned her back got a side view's code)
    if stored is not None and file_sha256(path) == model.codes_weights \
            and stored.get("view_pool") == retargeter.config.view_pool:
        codes = ReferenceCodes.from_dict(stored)
    else:
        log.info("computing the reference's codes from its stored track with %s", path)
        codes = retargeter.reference_codes(model.reference_track)
    return retargeter.retarget(driver, codes)


def global_scale_onto(driver: PoseTrack, model: ReferenceModel) -> PoseTrack:
    """The driver moved and scaled per frame onto the reference's feet positions (Everybody Dance Now)."""
    if model.scale_stats is None:
        raise InputError("the reference never shows its ankles, so --method global-scale is not available; "
                         "use --method retarget or none")
    return global_scale_to(driver, model.scale_stats, model.canvas.image_size)


def global_scale_to(driver: PoseTrack, target: ScaleStats, image_size: tuple[int, int]) -> PoseTrack:
    """The driver moved and scaled per frame onto a reference's scale statistics, in its ``image_size``."""
    layout = driver.joint_layout
    joints = apply_global_scale(driver.joints, layout, scale_stats(driver.joints, layout), target)
    return driver.replace(joints=joints, image_size=image_size)


def drive_poses(
    driver: PoseTrack, model: ReferenceModel, method: Method | str, weights: str | os.PathLike | None = None,
    device: str = "cpu", stage: StageMode | str = StageMode.FRAME, foot_lock: bool = True,
    refine_steps: int | None = None,
) -> tuple[PoseTrack, StageFit | None]:
    """The driver's poses in the reference's pixels, and how they were kept on the reference's stage.

    The network and global scaling move body15; when the driver is body31 and the model draws details, the
    driver's face, hands and feet are then carried onto the result through their parent bones
    (:func:`pose_io.details.carry_details`).

    Args:
        driver: the driver's track (body15, or body31 with details).
        model: the reference model.
        method: one of :data:`METHODS`.
        weights: retargeting weights (see :func:`retargeting_weights`).
        device: where the retargeting network runs.
        stage: one of :data:`STAGES` (:mod:`clone.drive.stage`): ``frame`` keeps the ``retarget`` and
            ``global-scale`` results inside the model's picture with their travel (a retargeted track starting
            where the reference stands), ``reference`` on the part of the frame the reference occupied, ``raw``
            as the method gave them.
        foot_lock: clean up the ``retarget`` result's foot skating with the driver's foot contacts
            (:func:`pose_io.feet.lock_feet`), before the stage fit, which moves the whole track at once.
        refine_steps: motion-code refinement steps of ``retarget`` (see :func:`retarget_onto`).

    Returns:
        ``(track, fit)``; ``fit`` is None when the stage was not applied (``raw``, or ``--method none``).
    """
    try:
        method, stage = Method(method), StageMode(stage)
    except ValueError:
        if method not in METHODS:
            raise InputError(f"unknown --method {method!r}; valid: {', '.join(METHODS)}") from None
        raise InputError(f"unknown --stage {stage!r}; valid: {', '.join(STAGES)}") from None
    if method is Method.NONE:
        if driver.image_size != model.canvas.image_size:
            log.warning("driver frames are %dx%d, the reference's %dx%d; --method none uses the coordinates "
                        "as they are", *driver.image_size, *model.canvas.image_size)
        return driver.replace(image_size=model.canvas.image_size), None
    body = driver.to_layout(LAYOUT)
    if method is Method.RETARGET:
        driven = retarget_onto(body, model, weights, device, refine_steps)
    else:
        driven = global_scale_onto(body, model)
    driven, fit = finish_driven(driven, body, model.reference_track, method is Method.RETARGET, stage, foot_lock,
                                picture_of(model.canvas))
    if driver.layout == DETAIL_LAYOUT and model.pose_layout == DETAIL_LAYOUT:
        driven = with_details(driven, driver)
    return driven, fit


def with_details(driven: PoseTrack, driver: PoseTrack) -> PoseTrack:
    """A driven body15 track with the body31 driver's face, hands and feet carried onto it (body31)."""
    from pose_io.details import carry_details

    joints = carry_details(driven.joints, driver.joints, driver.joint_layout)
    confidence = np.zeros(joints.shape[:2], dtype=np.float32)
    confidence[:, : driven.joints.shape[1]] = driven.confidence
    extra = slice(driven.joints.shape[1], None)
    confidence[:, extra] = np.where(np.isfinite(joints[:, extra, 0]), driver.confidence[:, extra], 0.0)
    return PoseTrack(joints, confidence, driven.fps, driven.image_size, DETAIL_LAYOUT)


def picture_of(canvas: Canvas) -> tuple[float, float, float, float]:
    """``(x0, y0, x1, y1)`` in image pixels: what of the reference's frame its model's canvas shows."""
    w, h = canvas.image_size
    return (max(0.0, canvas.x0), max(0.0, canvas.y0), min(w - 1.0, canvas.x0 + canvas.side - 1.0),
            min(h - 1.0, canvas.y0 + canvas.side - 1.0))


def finish_driven(
    driven: PoseTrack, driver: PoseTrack, reference: PoseTrack, retargeted: bool,
    stage: StageMode | str = StageMode.FRAME, foot_lock: bool = True,
    picture: tuple[float, float, float, float] | None = None,
) -> tuple[PoseTrack, StageFit | None]:  # fmt: skip
    """What follows moving the driver onto the reference: a retargeted track's foot skating cleaned with the
    driver's contacts (``foot_lock``), then (unless ``raw``) it starts where the reference stands, and the
    whole track is kept in bounds (``stage``, :mod:`clone.drive.stage`).

    Args:
        picture: ``(x0, y0, x1, y1)``, the picture ``frame`` keeps the track in (default: the reference's
            whole frame, ``reference.image_size``).

    Returns:
        ``(track, fit)`` as :func:`drive_poses`.
    """
    if retargeted and foot_lock:
        from pose_io.feet import lock_feet

        driven = lock_feet(driven, driver)
    stage = StageMode(stage)
    if stage is StageMode.RAW:
        return driven, None
    if retargeted:
        driven = start_on_reference(driven, reference)
    if stage is StageMode.REFERENCE:
        return fit_to_stage(driven, reference)
    if picture is None:
        w, h = reference.image_size
        picture = (0.0, 0.0, w - 1.0, h - 1.0)
    return fit_to_stage(driven, reference, picture=picture)


def move_onto_reference(
    driver: PoseTrack, model: ReferenceModel, method: Method | str, weights: str | os.PathLike | None = None,
    device: str = "cpu", stage: StageMode | str = StageMode.FRAME, foot_lock: bool = True,
    refine_steps: int | None = None,
) -> PoseTrack:
    """The driver's poses in the reference's pixels (see :func:`drive_poses`, which also says how far they
    were moved to stay on the reference's stage)."""
    return drive_poses(driver, model, method, weights, device, stage, foot_lock, refine_steps)[0]
