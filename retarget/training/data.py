"""What training reads: cross samples of a world split, real-track windows, normalisation statistics, body
scales, the validation set and the data loader of one epoch."""

from __future__ import annotations

import logging
from collections import Counter
from collections.abc import Iterator, Sequence
from pathlib import PurePosixPath
from typing import Protocol

import numpy as np
import torch
from torch.utils.data import DataLoader, Dataset

from pose_io.errors import InputError
from pose_io.measures import skeleton_heights
from pose_io.track import PoseTrack
from retarget.inference.tracks import prepare_track
from retarget.network.model import variant_config
from retarget.network.preprocess import LAYOUT, LOCAL_INDEX, NormStats, PreprocessConfig, row_statistics
from retarget.training.augment import COMBOS
from retarget.training.config import TrainConfig
from retarget.world.camera import FRONTAL_YAW, WORLD_CAMERAS, CameraSpread
from retarget.world.split import WindowLabel
from retarget.world.turns import apply_turn, draw_turn
from retarget.world.variations import bend, draw_bend, splice

log = logging.getLogger(__name__)


class WorldSplit(Protocol):
    """What training needs from a split of the motion world."""

    num_motions: int
    num_characters: int
    num_views: int
    views: tuple[float, ...]  # yaw of each view bin (degrees); read only for a frontal share
    window_labels: tuple[WindowLabel, ...]  # read only for a source balance

    def window(
        self, motion: int, character: int, view: int, length: int = 64, offset: int = 0,
        rng: np.random.Generator | None = None, *, cameras: CameraSpread = WORLD_CAMERAS,
    ) -> np.ndarray: ...

    # Read only when samples turn (``CrossSamples(turns=...)``).
    def window3d(self, motion: int, character: int, length: int | None = None, offset: int = 0) -> np.ndarray: ...

    def project(self, pos: np.ndarray, views: Sequence[int] | np.ndarray, rng: np.random.Generator | None = None,
                pitch_deg: Sequence[float] | None = None, cameras: CameraSpread = WORLD_CAMERAS) -> np.ndarray: ...


class CrossSamples(Dataset):
    """Samples of two (motion, character, view) triples and the windows of their 8 combinations.

    Sample ``index`` of epoch ``epoch`` is a pure function of (seed, epoch, index), so training resumes
    exactly and data-loader workers need no shared state. The two motions always differ; characters
    (views) differ when the network has a skeleton (view) encoder, and are shared otherwise. Every
    window of one view is seen through the same camera (the world's ``rng`` draws the camera pitch).

    Args:
        split: a world split.
        length: frames per window.
        variant: network variant.
        size: samples per epoch.
        seed: seed.
        scales: optional [C] factor per character (body-height normalisation), applied about the origin.
        cameras: how each view slot's camera is drawn (default: the world's own). With another spread and
            ``scales``, a window is brought to ``height`` by its own skeleton height instead, as inference
            brings a track: a steep or near camera changes how tall a character looks.
        height: the skeleton height (canvas pixels) ``scales`` bring characters to.
        frontal: share of samples whose views are both drawn from the bins within :data:`FRONTAL_YAW` of the
            front (the split's ``views`` give the bins' yaws); the others draw from every bin.
        turns: share of motions given a whole-body turn in 3D before projection
            (:func:`retarget.world.turns.draw_turn`); every window of a turned motion turns alike.
        turn_range: the turns' angles, degrees (either way).
        splices: share of motions whose torso, arms and head come from another motion of the split
            (:func:`retarget.world.variations.splice`, on the same character).
        bend_deg: when above 0, every motion's upper-body joint angles get smooth noise of this many degrees
            (:func:`retarget.world.variations.bend`); the legs keep theirs.
        source_balance: the power of :func:`source_weights` the two motions of a sample are drawn with (0: every
            window alike, drawing exactly what runs before the option drew).
    """

    def __init__(
        self, split: WorldSplit, length: int, variant: str, size: int, seed: int, scales: np.ndarray | None = None,
        cameras: CameraSpread = WORLD_CAMERAS, height: float | None = None, frontal: float = 0.0,
        turns: float = 0.0, turn_range: tuple[float, float] = (90.0, 360.0), splices: float = 0.0,
        bend_deg: float = 0.0, source_balance: float = 0.0,
    ) -> None:
        if split.num_motions < 2:
            raise InputError(f"the motion world split has {split.num_motions} motion(s); training needs 2 or more")
        config = variant_config(variant)
        self.split = split
        self.length = length
        self.size = size
        self.seed = seed
        self.scales = scales
        self.cameras = cameras
        # Only a non-default spread is passed on: any WorldSplit (and test doubles) takes the default.
        self._camera_kwargs = {} if cameras == WORLD_CAMERAS else {"cameras": cameras}
        self.own_height = bool(self._camera_kwargs) and scales is not None
        if self.own_height and not (height is not None and height > 0):
            raise ValueError("a camera spread with body scales needs the target height")
        self.height = height
        self.epoch = 0
        self.vary_character = config.body_channels is not None and split.num_characters > 1
        self.vary_view = config.view_channels is not None and split.num_views > 1
        if not 0 <= frontal <= 1:
            raise ValueError("frontal must be a share in [0, 1]")
        self.frontal = frontal
        if not 0 <= turns <= 1:
            raise ValueError("turns must be a share in [0, 1]")
        self.turns = turns
        self.turn_range = tuple(turn_range)
        if not 0 <= splices <= 1:
            raise ValueError("splices must be a share in [0, 1]")
        if bend_deg < 0:
            raise ValueError("bend_deg must be >= 0")
        self.splices = splices
        self.bend_deg = bend_deg
        if not 0 <= source_balance <= 1:
            raise ValueError("source_balance must be in [0, 1]")
        self.motion_weights = source_weights(split.window_labels, source_balance) if source_balance > 0 else None
        self.frontal_views = np.arange(split.num_views)
        if frontal > 0:
            self.frontal_views = np.flatnonzero(np.abs(np.asarray(split.views)) <= FRONTAL_YAW)
            need = 2 if self.vary_view else 1
            if len(self.frontal_views) < need:
                raise InputError(f"the split has {len(self.frontal_views)} view(s) within {FRONTAL_YAW:g} degrees "
                                 f"of the front; a frontal share needs {need}")

    def __len__(self) -> int:
        return self.size

    def sample(self, epoch: int, index: int) -> dict[str, np.ndarray]:
        """{"windows": [8, length, 15, 2] float32 (order of :data:`COMBOS`), "ids": [2, 3] int64}."""
        rng = np.random.default_rng([self.seed, epoch, index])
        motions = rng.choice(self.split.num_motions, 2, replace=False, p=self.motion_weights)
        chars = _pair(rng, self.split.num_characters, self.vary_character)
        # Without a frontal share no extra number is drawn: runs before it draw the same samples.
        if self.frontal > 0 and rng.random() < self.frontal:
            views = self.frontal_views[_pair(rng, len(self.frontal_views), self.vary_view)]
        else:
            views = _pair(rng, self.split.num_views, self.vary_view)
        # The world's `rng` perturbs the camera (pitch): a fresh generator per view slot gives every
        # window seen from one view the same camera.
        view_seeds = rng.integers(0, 2**63 - 1, size=2)
        if views[0] == views[1]:
            view_seeds[1] = view_seeds[0]
        # Turns draw from their own generator: without them the samples are those of runs before they existed.
        turning = np.random.default_rng([self.seed, epoch, index, 15485863]) if self.turns > 0 else None
        turns = [draw_turn(turning, self.length, self.turn_range) if turning is not None
                 and turning.random() < self.turns else None for _ in range(2)]  # fmt: skip
        donors, bends = self._variations(epoch, index, motions)
        cache: dict[tuple[int, int, int], np.ndarray] = {}
        windows = []
        for m, c, v in COMBOS:
            key = (int(motions[m]), int(chars[c]), int(views[v]))
            if key not in cache:
                camera = np.random.default_rng(int(view_seeds[v]))
                if turns[m] is None and donors[m] is None and bends[m] is None:
                    window = self.split.window(*key, length=self.length, offset=0, rng=camera, **self._camera_kwargs)
                else:
                    pos = self.split.window3d(key[0], key[1], self.length)
                    if donors[m] is not None:
                        pos = splice(pos, self.split.window3d(donors[m], key[1], self.length))
                    if bends[m] is not None:
                        pos = bend(pos, bends[m])
                    if turns[m] is not None:
                        pos = apply_turn(pos, turns[m])
                    window = self.split.project(pos[None], [key[2]], camera, cameras=self.cameras)[0]
                if self.own_height:
                    window = window * (self.height / skeleton_heights(window[None], LAYOUT)[0])
                elif self.scales is not None:
                    window = window * self.scales[key[1]]
                cache[key] = np.asarray(window, np.float32)
            windows.append(cache[key])
        ids = np.stack([motions, chars, views], axis=1).astype(np.int64)  # [2, 3]
        return {"windows": np.stack(windows), "ids": ids}

    def __getitem__(self, index: int) -> dict[str, np.ndarray]:
        return self.sample(self.epoch, index)

    def _variations(self, epoch: int, index: int, motions: np.ndarray) -> tuple[list, list]:
        """Per motion slot of a sample: the motion its upper body comes from (or None) and its bend's rotation
        vectors (or None). Drawn from a stream of their own, once per slot, so both characters of a motion
        move alike; without either variation nothing is drawn."""
        donors: list[int | None] = [None, None]
        bends: list[np.ndarray | None] = [None, None]
        if self.splices <= 0 and self.bend_deg <= 0:
            return donors, bends
        rng = np.random.default_rng([self.seed, epoch, index, 32452843])
        for m in range(2):
            if self.splices > 0 and rng.random() < self.splices:
                donor = int(rng.integers(self.split.num_motions - 1))
                donors[m] = donor + (donor >= motions[m])  # any motion but its own
            if self.bend_deg > 0:
                bends[m] = draw_bend(rng, self.length, self.bend_deg)
        return donors, bends


def window_source(label: WindowLabel) -> str:
    """The motion-capture source of a window: the top folder of its clip's path under the mocap folder ("" for a
    clip at its top level)."""
    parts = PurePosixPath(label.path.replace("\\", "/")).parts
    return parts[0] if len(parts) > 1 else ""


def source_weights(labels: Sequence[WindowLabel], power: float) -> np.ndarray:
    """[N] probabilities of drawing each of N windows: proportional to ``count ** -power``, ``count`` being the
    windows of its source (:func:`window_source`), so the sources' shares go as ``count ** (1 - power)``."""
    sources = [window_source(label) for label in labels]
    counts = Counter(sources)
    weights = np.array([counts[s] ** -float(power) for s in sources])
    return weights / weights.sum()


def _pair(rng: np.random.Generator, n: int, distinct: bool) -> np.ndarray:
    if distinct:
        return rng.choice(n, 2, replace=False)
    return np.repeat(rng.integers(n), 2)


def split_statistics(
    split: WorldSplit, length: int, count: int, seed: int, scales: np.ndarray | None = None
) -> NormStats:
    """Normalisation statistics of ``count`` random windows of a split (each scaled by its character's factor)."""
    rng = np.random.default_rng([seed, 7919])
    windows = []
    for _ in range(count):
        m, c, v = (int(rng.integers(n)) for n in (split.num_motions, split.num_characters, split.num_views))
        window = split.window(m, c, v, length=length, offset=0, rng=rng)
        windows.append(window * (1.0 if scales is None else scales[c]))
    return row_statistics(np.stack(windows))


def character_heights(split: WorldSplit, length: int, per_character: int, seed: int) -> np.ndarray:
    """[C] median skeleton height (canvas pixels) of each character over ``per_character`` random windows."""
    rng = np.random.default_rng([seed, 3571])
    heights = np.empty(split.num_characters)
    for c in range(split.num_characters):
        windows = np.stack([
            split.window(int(rng.integers(split.num_motions)), c, int(rng.integers(split.num_views)),
                         length=length, offset=0, rng=rng)
            for _ in range(per_character)
        ])  # fmt: skip
        heights[c] = np.nanmedian(skeleton_heights(windows, LAYOUT))
    return heights


def mean_pose_height(stats: NormStats) -> float:
    """Skeleton height of the mean pose that normalisation statistics describe (canvas pixels)."""
    joints = np.zeros((1, 1, len(LAYOUT), 2))
    joints[0, 0, list(LOCAL_INDEX)] = stats.mean[:-1]
    return float(skeleton_heights(joints, LAYOUT)[0])


def body_scales(split: WorldSplit, config: TrainConfig, target: float) -> np.ndarray | None:
    """[C] factor bringing each character of ``split`` to ``target`` skeleton height (None: no normalisation)."""
    if not config.body_normalise:
        return None
    return target / character_heights(split, config.window, 8, config.seed)


def real_windows(tracks: Sequence[PoseTrack], length: int, preprocess: PreprocessConfig) -> np.ndarray:
    """Overlapping windows (half-window steps) of real tracks in the canvas: [N, length, 15, 2] float32."""
    out = []
    for i, track in enumerate(tracks):
        if len(track) < length:
            log.warning("real track %d has %d frames (< %d); skipped", i, len(track), length)
            continue
        joints = prepare_track(track, preprocess, f"real track {i}")
        out += [joints[s : s + length] for s in range(0, len(joints) - length + 1, max(1, length // 2))]
    return np.asarray(out, dtype=np.float32).reshape(-1, length, 15, 2)



def validation_set(
    split: WorldSplit, config: TrainConfig, scales: np.ndarray | None
) -> tuple[torch.Tensor, torch.Tensor] | None:
    """The fixed validation samples of a run: ``config.val_samples`` cross samples of ``split`` (seed + 1) as
    ``(windows [N, 8, T, 15, 2], ids [N, 2, 3])``; None when the split has fewer than two motions."""
    if split.num_motions < 2:
        log.warning("validation split has fewer than 2 motions; no validation")
        return None
    samples = CrossSamples(split, config.window, config.variant, config.val_samples, config.seed + 1, scales)
    items = [samples.sample(0, i) for i in range(config.val_samples)]
    windows = torch.from_numpy(np.stack([it["windows"] for it in items]))  # [N, 8, T, 15, 2]
    ids = torch.from_numpy(np.stack([it["ids"] for it in items]))  # [N, 2, 3]
    return windows, ids


def batch_loader(
    dataset: CrossSamples, first_step: int, steps: int, batch_size: int, workers: int, part: slice | None = None,
    pin: bool = False,
) -> Iterator:
    """Batches of steps ``first_step`` to ``steps``; with ``part``, this process's samples of each global batch.

    Step s of an epoch is samples ``[s * batch_size, (s + 1) * batch_size)`` whatever the number of
    processes; a process takes ``part`` of them.
    """
    if part is None or (part.start, part.stop) == (0, batch_size):
        indices: Sequence[int] = range(first_step * batch_size, steps * batch_size)
        per_step = batch_size
    else:
        indices = [s * batch_size + i for s in range(first_step, steps) for i in range(part.start, part.stop)]
        per_step = part.stop - part.start
    # Its own generator: a loader would otherwise draw its worker seed from the global RNG, and a resumed
    # run would then drop out differently. Samples depend on (seed, epoch, index) only.
    loader = DataLoader(dataset, batch_size=per_step, sampler=indices, num_workers=workers, drop_last=True,
                        generator=torch.Generator(), pin_memory=pin)
    return iter(loader)
