"""What motion retrieval compares: a feature sequence ``[C, T / stride]`` per pose track.

Two encoders, one interface, so the search and its baseline run the same cross-correlation:

- :class:`MotionCodeEncoder`: the retargeting network's motion code (``encode_motion``: ``[1, 30, T] ->
  [1, 128, T/8]``), which the network learnt to keep free of the performer's body and of the view.
- :class:`JointEncoder`: the baseline, root-relative body15 joints divided by the body height
  (:func:`pose_io.measures.skeleton_height`), one step per frame; it cannot ignore body and view.

Every track is first brought to the encoder's frame rate (:func:`pose_io.resample.resample`), so tracks filmed
at 25 and 60 fps compare with each other; frame numbers are mapped back to each track's own frames by the
search. A track longer than ``chunk`` frames is encoded in overlapping pieces whose seams are cut away, so
memory stays bounded and the codes are those of one pass over the whole track.
"""

from __future__ import annotations

import hashlib
from typing import Protocol

import numpy as np
import torch
import torch.nn.functional as F

from pose_io.errors import InputError
from pose_io.measures import skeleton_height
from pose_io.resample import resample
from pose_io.track import PoseTrack
from retarget.api import Retargeter
from retarget.inference.config import NETWORK_FPS
from retarget.inference.tracks import prepare_track
from retarget.network.preprocess import LAYOUT, LOCAL_INDEX, ROOT_INDEX, PreprocessConfig

#: Frame rate every track is resampled to before encoding: the one the network was trained at.
ENCODE_FPS = NETWORK_FPS


class TrackEncoder(Protocol):
    """Turns pose tracks into feature sequences for :mod:`retarget.applications.search`.

    Attributes:
        kind: name stored in the index (``"motion"`` or ``"joints"``).
        stride: input frames per feature step.
        fps: frame rate tracks are resampled to before encoding.
        digest: identity of the encoder's parameters (an index only answers queries of the same encoder).
        min_frames: shortest track (at ``fps``) it encodes.
    """

    kind: str
    stride: int
    fps: float
    digest: str
    min_frames: int

    def inputs(self, track: PoseTrack, name: str) -> torch.Tensor:
        """[1, Cin, T] per-frame inputs of a track already at :attr:`fps`."""
        ...

    def encode(self, x: torch.Tensor) -> torch.Tensor:
        """[B, Cin, T] (T a multiple of :attr:`stride`) -> [B, C, T / stride] float32."""
        ...


class MotionCodeEncoder:
    """The motion encoder of a loaded retargeting network.

    Args:
        retargeter: from :func:`retarget.api.load_retargeter`.
        chunk: frames per network pass for long tracks (a multiple of 8).
    """

    kind = "motion"
    fps = ENCODE_FPS

    def __init__(self, retargeter: Retargeter, chunk: int = 4096) -> None:
        self.retargeter = retargeter
        self.stride = retargeter.model.config.downsampling
        self.min_frames = retargeter.min_frames
        self.chunk = chunk
        # Frames of real context each side of a piece: more than the encoder's receptive field (50 frames for
        # the paper's three layers of kernel 8), rounded to the stride so pieces stay on the code grid.
        kernel, layers = retargeter.model.config.motion_kernel, len(retargeter.model.config.motion_channels) - 1
        reach = (kernel - 1) * (2**layers - 1) + 1
        self.margin = -(-reach // self.stride) * self.stride
        self.digest = model_digest(retargeter)

    def inputs(self, track: PoseTrack, name: str) -> torch.Tensor:
        return self.retargeter._input(track, name)  # [1, 30, T]

    @torch.inference_mode()
    def encode(self, x: torch.Tensor) -> torch.Tensor:
        model, s = self.retargeter.model, self.stride
        length = x.shape[-1]
        if length <= self.chunk + 2 * self.margin:
            return model.encode_motion(x.to(self.retargeter.device)).float().cpu()
        pieces = []
        for a in range(0, length, self.chunk):
            b = min(a + self.chunk, length)
            lo, hi = max(0, a - self.margin), min(length, b + self.margin)
            codes = model.encode_motion(x[:, :, lo:hi].to(self.retargeter.device))  # [B, C, (hi - lo) / s]
            pieces.append(codes[:, :, (a - lo) // s : (b - lo) // s].float().cpu())
        return torch.cat(pieces, dim=-1)  # [B, C, T / s]


class JointEncoder:
    """The raw-joint baseline: root-relative body15 joints over the body height, 28 channels per frame.

    Args:
        preprocess: gap filling and smoothing the tracks get (default: the paper's, as the network's input).
    """

    kind = "joints"
    stride = 1
    fps = ENCODE_FPS
    digest = "joints-v1"
    min_frames = 2

    def __init__(self, preprocess: PreprocessConfig | None = None) -> None:
        self.preprocess = preprocess if preprocess is not None else PreprocessConfig()

    def inputs(self, track: PoseTrack, name: str) -> torch.Tensor:
        if len(track) < self.min_frames:
            raise InputError(f"{name}: {len(track)} frames; the search needs at least {self.min_frames}")
        joints = prepare_track(track, self.preprocess, name)  # [T, 15, 2] canvas, gaps filled
        local = joints[:, list(LOCAL_INDEX)] - joints[:, ROOT_INDEX : ROOT_INDEX + 1]  # [T, 14, 2]
        local = local / skeleton_height(joints, LAYOUT)
        return torch.from_numpy(local.reshape(len(local), -1).T.copy()).float()[None]  # [1, 28, T]

    def encode(self, x: torch.Tensor) -> torch.Tensor:
        return x.float()


def model_digest(retargeter: Retargeter) -> str:
    """Short SHA-256 of a network's parameters, statistics and preprocessing: which codes an index holds."""
    h = hashlib.sha256()
    for key, value in sorted(retargeter.model.state_dict().items()):
        h.update(key.encode())
        h.update(value.detach().cpu().contiguous().numpy().tobytes())
    h.update(retargeter.stats.mean.tobytes())
    h.update(retargeter.stats.std.tobytes())
    h.update(repr(retargeter.preprocess).encode())
    return h.hexdigest()[:16]


def at_encoder_fps(track: PoseTrack, encoder: TrackEncoder) -> PoseTrack:
    """``track`` resampled to the encoder's frame rate (unchanged when it already has it)."""
    return track if abs(track.fps - encoder.fps) < 1e-6 else resample(track, encoder.fps)


def track_features(encoder: TrackEncoder, track: PoseTrack, name: str = "track") -> np.ndarray:
    """Feature sequence of a whole track, for the index.

    The track is resampled to the encoder's rate and padded at its end (reflection) to a multiple of the
    stride, so feature step ``k`` starts at frame ``k * stride`` of the resampled track.

    Args:
        encoder: a :class:`TrackEncoder`.
        track: any layout that gives body15, at least ``encoder.min_frames`` long at the encoder's rate.
        name: how error messages call it.

    Returns:
        [C, ceil(T' / stride)] float32, T' the resampled length.

    Raises:
        InputError: too short, a layout without body15, or joints never detected.
    """
    x = encoder.inputs(at_encoder_fps(track, encoder), name)  # [1, Cin, T']
    extra = -x.shape[-1] % encoder.stride
    if extra:
        x = F.pad(x, (0, extra), mode="reflect")  # [1, Cin, T8]
    return encoder.encode(x)[0].numpy()


def query_features(
    encoder: TrackEncoder, track: PoseTrack, phase_step: int = 1, name: str = "query"
) -> tuple[np.ndarray, np.ndarray]:
    """Feature sequences of a query at every phase of the stride grid.

    A query cut from an indexed track rarely starts on that track's feature grid; phase ``p`` drops the
    query's first ``p`` frames, and the phase that lands on the grid gives the codes the index holds.

    Args:
        encoder: a :class:`TrackEncoder`.
        track: the query.
        phase_step: frames between phases (1 = every phase; ``stride`` = one phase).
        name: how error messages call it.

    Returns:
        (features [P, C, L] float32, phases [P] int64 frames dropped at the query's start, at the encoder's rate).

    Raises:
        InputError: the query is shorter than the encoder needs (``min_frames`` at the encoder's rate).
    """
    x = encoder.inputs(at_encoder_fps(track, encoder), name)  # [1, Cin, T']
    s, frames = encoder.stride, x.shape[-1]
    phases = np.arange(0, s, max(1, min(phase_step, s)), dtype=np.int64)
    phases = phases[frames - phases >= encoder.min_frames]  # a short query tries only the phases it can fill
    if not len(phases):
        raise InputError(
            f"{name}: {len(track)} frames ({frames} at {encoder.fps:g} fps); a query needs at least"
            f" {encoder.min_frames} at {encoder.fps:g} fps"
        )
    steps = (frames - int(phases[-1])) // s
    batch = torch.cat([x[:, :, p : p + steps * s] for p in phases])  # [P, Cin, L * s]
    return encoder.encode(batch).numpy(), phases
