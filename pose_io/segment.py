"""The person's own silhouette, from MediaPipe's selfie segmentation (inside the mediapipe wheel; no download).

A pose says where the joints are, not where the hair, the dress or the hands reach; the segmentation does. The
background plate of a reference (:mod:`clone.model.background`) takes it so that a long dress or loose hair the
person never moved out of does not end up painted into the background.
"""

from __future__ import annotations

import logging
import warnings
from collections.abc import Iterable

import numpy as np

from pose_io.errors import InputError, raise_if_interrupted
from pose_io.quiet import quiet_native_logs

log = logging.getLogger(__name__)

THRESHOLD = 0.5  # MediaPipe's mask is a per-pixel probability of the person


def segmentation_available() -> bool:
    """Whether MediaPipe's selfie segmentation can be imported."""
    try:
        _load()
    except InputError:
        return False
    return True


def _load():  # the selfie_segmentation module
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            from mediapipe.python.solutions import selfie_segmentation
    except ImportError as exc:
        raise_if_interrupted(exc)
        from pose_io.extract import INSTALL_HINT

        raise InputError(INSTALL_HINT.replace("pose extraction", "person segmentation")) from None
    return selfie_segmentation


def person_masks(frames: Iterable[np.ndarray], threshold: float = THRESHOLD) -> np.ndarray:
    """[N, H, W] bool: where each [H, W, 3] uint8 RGB frame shows the person (all frames one size).

    Raises:
        InputError: MediaPipe is not installed, or no frames.
    """
    module = _load()
    masks = []
    with quiet_native_logs(), warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # protobuf deprecation noise from inside mediapipe
        with module.SelfieSegmentation(model_selection=0) as segmenter:
            for frame in frames:
                result = segmenter.process(np.ascontiguousarray(frame))
                mask = result.segmentation_mask
                masks.append(np.zeros(frame.shape[:2], bool) if mask is None else mask > threshold)
    if not masks:
        raise InputError("person segmentation: no frames")
    return np.stack(masks)
