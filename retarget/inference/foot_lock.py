"""Retargeting with the foot-contact cleanup (``pose_io.feet``): `clone retarget apply`'s default.

A thin wrapper around either backend. It finds each driver's foot contacts while the driver is prepared (the
batch path keeps only the network input of a track after that, :func:`retarget.inference.batch.retarget_files`) and cleans
every result with them. numpy only: the numpy backend stays torch-free.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pose_io.feet import DEFAULT_FOOT_LOCK, FootLockConfig, foot_lock, track_contacts
from pose_io.track import PoseTrack
from retarget.inference.algorithm import RetargeterBase
from retarget.inference.config import PreparedMotion, ReferenceCodes


@dataclass(frozen=True, eq=False)
class LockedMotion(PreparedMotion):
    """A prepared driver that also keeps its foot contacts ([T, 2] bool, ``ANKLES`` order)."""

    contacts: np.ndarray | None = None


class FootLockedRetargeter:
    """``prepare_motion`` / ``retarget_prepared`` / ``retarget`` of ``inner``, each result foot-locked.

    Args:
        inner: either backend.
        config: contact test and cleanup settings.
    """

    def __init__(self, inner: RetargeterBase, config: FootLockConfig = DEFAULT_FOOT_LOCK) -> None:
        self.inner = inner
        self.config = config

    def prepare_motion(self, motion: PoseTrack, name: str = "motion track") -> LockedMotion:
        """The network input of ``motion`` (``inner``'s) with its foot contacts."""
        prepared = self.inner.prepare_motion(motion, name)
        return LockedMotion(prepared.x, prepared.fps, prepared.name, prepared.frames, prepared.rate,
                            track_contacts(motion, self.config))

    def retarget_prepared(self, motions: Sequence[LockedMotion], reference: ReferenceCodes) -> list[PoseTrack]:
        """``inner``'s results for motions prepared by this wrapper, each cleaned with its driver's contacts."""
        results = self.inner.retarget_prepared(motions, reference)
        return [r.replace(joints=foot_lock(r.joints, m.contacts, r.layout, self.config)) for r, m in zip(results, motions)]

    def retarget(self, motion: PoseTrack, reference: ReferenceCodes, *, name: str = "motion track") -> PoseTrack:
        """``inner.retarget`` of one track, foot-locked."""
        return self.retarget_prepared([self.prepare_motion(motion, name)], reference)[0]
