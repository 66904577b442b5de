"""Latent interpolation (Aberman et al. 2019, Fig. 1 and Sec. 6): a grid of two clips' codes blended.

Clips A and B each give a motion code (it varies over time), a skeleton code and a view code. Two of the
three attributes are blended linearly, ``(1 - w) * A + w * B`` with ``w = linspace(0, 1, steps)``: the first
along the grid's rows, the second along its columns; the third stays A's. Every cell is decoded into a pose
sequence, so cell ``[0, 0]`` is A's own codes and cell ``[-1, -1]`` has B's codes for both varied attributes.

A motion code has one column per 8 frames, so blending it needs clips of equal length: both are cut to the
shorter one (and to at most ``frames`` frames, the authors' ``--max_length``) before anything else is done
with them, B first resampled to A's frame rate when they differ (``video`` canvas).

Two canvases, i.e. two conventions for codes and output:

* ``video`` (default), as `clone retarget apply` does it: skeleton and view codes are a reference's
  (:meth:`Retargeter.reference_codes`: the mean over windows, the view code the window code nearest it), the poses are in A's pixels, smoothed over time like retargeted tracks
  and standing where A stands; like retargeting, the network runs at its own frame rate (A and B are resampled
  to it when A's is another) and the poses come back at A's frames. A cell whose codes all come from whole clips
  is plain retargeting with those
  codes, drawn in A's frame, by the encoders' motion codes: the grid explores the latent space as the encoders
  map it, without the test-time refinement of motion codes that retargeting does by default (so a corner is
  ``retarget`` with ``InferenceConfig.refine_steps`` 0, exactly so up to the retargeter's window: the grid
  decodes in one pass, long retargeting runs in cross-faded windows).
* ``authors``, the authors' ``interpolate.py`` (ChrisWu1997/2D-Motion-Retargeting): static codes from one pass
  over the whole clip, the network on the unpadded clip (it gives 8 * floor(T / 8) frames), poses in the
  network's canvas (512 pixels) with the root starting at its centre (256, 256), not smoothed.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator
from dataclasses import dataclass

import cv2
import numpy as np
import torch

from pose_io.clean import smooth_joints
from pose_io.draw import blank_canvas, draw_pose
from pose_io.errors import InputError
from pose_io.resample import resample, resample_values
from pose_io.track import PoseTrack
from retarget.api import Retargeter, _pad_to_multiple
from retarget.inference.placement import place
from retarget.network.preprocess import LAYOUT, channels_to_joints

log = logging.getLogger(__name__)

ATTRIBUTES: tuple[str, ...] = ("motion", "body", "view")
CANVASES: tuple[str, ...] = ("video", "authors")
MAX_STEPS = 16


@dataclass(frozen=True)
class LatentCodes:
    """The three codes of a batch of clips.

    Attributes:
        motion: [B, Cm, T'] motion code.
        body: [B, Cb, 1] skeleton code.
        view: [B, Cv, 1] view code.
    """

    motion: torch.Tensor
    body: torch.Tensor
    view: torch.Tensor

    def chunks(self, size: int) -> Iterator[LatentCodes]:
        """Batches of at most ``size`` clips."""
        for start in range(0, self.motion.shape[0], size):
            cut = slice(start, start + size)
            yield LatentCodes(self.motion[cut], self.body[cut], self.view[cut])


@dataclass(frozen=True, eq=False)
class LatentGrid:
    """Decoded cells of an interpolation grid.

    Attributes:
        poses: [S, S, T, 15, 2] float64 body15 poses; ``poses[i, j]`` blends the row attribute with weight
            ``weights[i]`` and the column attribute with ``weights[j]``.
        weights: [S] weight of B along each axis (0 = A's code, 1 = B's).
        rows: attribute blended down the rows.
        cols: attribute blended across the columns.
        kept: attribute that is A's in every cell.
        canvas: "video" (A's pixels) or "authors" (the network canvas).
        image_size: (width, height) of the frame the poses are in.
        fps: frame rate (A's).
        names: how to call A and B in labels.
    """

    poses: np.ndarray
    weights: np.ndarray
    rows: str
    cols: str
    kept: str
    canvas: str
    image_size: tuple[int, int]
    fps: float
    names: tuple[str, str] = ("A", "B")

    def to_arrays(self) -> dict[str, np.ndarray]:
        """Plain arrays for an ``.npz`` (poses as float32, the layout's joint names included)."""
        return {
            "poses": self.poses.astype(np.float32), "weights": self.weights.astype(np.float64),
            "rows": np.array(self.rows), "cols": np.array(self.cols), "kept": np.array(self.kept),
            "canvas": np.array(self.canvas), "image_size": np.array(self.image_size, dtype=np.int64),
            "fps": np.float64(self.fps), "layout": np.array(LAYOUT.name), "joints": np.array(LAYOUT.joints),
            "names": np.array(self.names),
        }


def parse_vary(text: str) -> tuple[str, str]:
    """``"motion,view"`` -> ("motion", "view"): the row attribute, then the column attribute.

    Raises:
        InputError: not two different names of :data:`ATTRIBUTES`.
    """
    parts = tuple(p.strip().lower() for p in text.split(","))
    if len(parts) != 2 or parts[0] == parts[1] or not set(parts) <= set(ATTRIBUTES):
        raise InputError(
            f"--vary {text!r}: name two different attributes of {', '.join(ATTRIBUTES)} (e.g. motion,view)"
        )
    return parts[0], parts[1]


def blend_weights(steps: int) -> torch.Tensor:
    """[S] float32 weights of B, ``linspace(0, 1, steps)`` (the authors' ``alphas``)."""
    return torch.linspace(0.0, 1.0, steps)


def grid_codes(a: LatentCodes, b: LatentCodes, rows: str, cols: str, steps: int) -> LatentCodes:
    """The codes of every cell: ``(1 - w) * a + w * b`` per attribute, row-major.

    Args:
        a: codes of clip A (batch 1).
        b: codes of clip B (batch 1, same motion-code length).
        rows: attribute blended with ``weights[i]`` in row ``i``.
        cols: attribute blended with ``weights[j]`` in column ``j``.
        steps: S, cells per axis.

    Returns:
        [S * S, ...] codes; cell (i, j) is batch entry ``i * S + j``; the third attribute is A's.
    """
    w = blend_weights(steps).to(a.motion.device)
    per_cell = {
        rows: w.repeat_interleave(steps),  # [S*S]: row i's weight for cells i*S .. i*S+S-1
        cols: w.repeat(steps),  # [S*S]: column j's weight for cells j, S+j, ...
    }
    blended = {}
    for name in ATTRIBUTES:
        code_a, code_b = getattr(a, name), getattr(b, name)  # [1, C, T'] / [1, C, 1]
        if name not in per_cell:
            blended[name] = code_a.expand(steps * steps, *code_a.shape[1:])
            continue
        weight = per_cell[name].reshape(-1, 1, 1)  # [S*S, 1, 1]
        blended[name] = (1 - weight) * code_a + weight * code_b  # [S*S, C, T']
    return LatentCodes(**blended)


def interpolate_grid(
    retargeter: Retargeter,
    a: PoseTrack,
    b: PoseTrack,
    vary: tuple[str, str] = ("motion", "view"),
    steps: int = 5,
    frames: int = 120,
    canvas: str = "video",
    names: tuple[str, str] = ("A", "B"),
) -> LatentGrid:
    """Decode an ``steps x steps`` grid of codes blended between clips A and B.

    Args:
        retargeter: a full (three-encoder) network.
        a: clip A (any layout convertible to body15); its third attribute is kept in every cell.
        b: clip B.
        vary: (row attribute, column attribute), two of :data:`ATTRIBUTES`.
        steps: cells per axis (2 .. 16).
        frames: at most this many frames from the start of each clip.
        canvas: "video" or "authors" (see the module docstring).
        names: how error messages and labels call A and B.

    Returns:
        The grid; its poses are [S, S, T, 15, 2] with T = min(len(a), len(b), frames) ("video") or 8 * floor(T / 8)
        ("authors").

    Raises:
        InputError: bad settings, a network without all three encoders, or clips the network cannot take.
    """
    rows, cols = parse_vary(",".join(vary))
    kept = next(name for name in ATTRIBUTES if name not in (rows, cols))
    if canvas not in CANVASES:
        raise InputError(f"unknown canvas {canvas!r}; valid: {', '.join(CANVASES)}")
    if not 2 <= steps <= MAX_STEPS:
        raise InputError(f"steps must be in 2..{MAX_STEPS}, got {steps}")
    if retargeter.variant != "full":
        raise InputError(
            f"latent interpolation needs the full network (motion, skeleton and view encoders); this one is"
            f" the {retargeter.variant!r} network"
        )
    if canvas == "video" and abs(b.fps - a.fps) > 1e-6:
        log.info("resampling %s from %g to %g fps (%s's rate)", names[1], b.fps, a.fps, names[0])
        b = resample(b, a.fps)
    length = min(len(a), len(b), frames)
    if length < len(a) or length < len(b):
        log.info("both clips cut to their first %d frames", length)
    a, b = a.frames(0, length), b.frames(0, length)
    # the video canvas runs the network at its rate, as retargeting does (A and B now share fps and length)
    rate = retargeter._network_rate(a, names[0]) if canvas == "video" else None
    x = [retargeter._input(track, name, rate) for track, name in zip((a, b), names)]  # 2 x [1, 30, T']

    if canvas == "authors":
        codes, left = [_whole_clip_codes(retargeter, xi) for xi in x], 0
    else:
        references = [retargeter.reference_codes(track, name=name) for track, name in zip((a, b), names)]
        codes = [_padded_clip_codes(retargeter, xi, ref.body, ref.view) for xi, ref in zip(x, references)]
        left = _pad_to_multiple(x[0], retargeter.model.config.downsampling)[1]
    cells = grid_codes(codes[0], codes[1], rows, cols, steps)
    y = _decode(retargeter, cells)  # [S*S, 30, T8]
    if canvas == "authors":
        half = retargeter.preprocess.canvas_height / 2
        joints = channels_to_joints(y.double(), retargeter.stats, start=torch.tensor([half, half]))
        poses = joints.numpy()  # [S*S, T8, 15, 2] canvas pixels
        image_size = (int(2 * half), int(2 * half))
    else:
        joints = channels_to_joints(y[:, :, left : left + x[0].shape[-1]].double(), retargeter.stats).numpy()
        joints = joints / references[0].scale  # [S*S, T', 15, 2] A's pixels
        sigma, placement = retargeter.preprocess.output_sigma, references[0].placement
        poses = np.stack([place(smooth_joints(cell, sigma), placement) for cell in joints])
        if rate != a.fps:  # back to A's frames: [S*S, T, 15, 2]
            poses = np.stack([resample_values(cell, rate, a.fps, frames=length) for cell in poses])
        image_size = a.image_size
    poses = poses.reshape(steps, steps, *poses.shape[1:])  # [S, S, T, 15, 2]
    return LatentGrid(poses, blend_weights(steps).double().numpy(), rows, cols, kept, canvas, image_size,
                      a.fps, names)


@torch.inference_mode()
def _whole_clip_codes(retargeter: Retargeter, x: torch.Tensor) -> LatentCodes:
    """[1, 30, T] -> codes from one pass over the whole clip (the authors' way)."""
    model = retargeter.model
    return LatentCodes(model.encode_motion(x), model.encode_body(x), model.encode_view(x))


@torch.inference_mode()
def _padded_clip_codes(retargeter: Retargeter, x: torch.Tensor, body: np.ndarray, view: np.ndarray) -> LatentCodes:
    """[1, 30, T] and static codes [C] -> codes as :meth:`Retargeter.retarget` uses them without refinement
    (reflect-padded clip, the encoder's motion code)."""
    padded, _ = _pad_to_multiple(x, retargeter.model.config.downsampling)  # [1, 30, T8]
    return LatentCodes(
        retargeter.model.encode_motion(padded), retargeter._code_tensor(body), retargeter._code_tensor(view)
    )


@torch.inference_mode()
def _decode(retargeter: Retargeter, cells: LatentCodes) -> torch.Tensor:
    """[N] cells -> [N, 30, T8] decoded poses on the CPU, in batches of the retargeter's size."""
    outs = [retargeter.model.decode(c.motion, c.body, c.view) for c in cells.chunks(retargeter.config.batch)]
    return torch.cat(outs).float().cpu()


# ---------------------------------------------------------------------------------------------------------
# Drawing: one video frame per time step, every cell a small canvas, the axes labelled.

_TEXT = (235, 235, 235)
_GRID_LINE = (70, 70, 70)
_FONT = cv2.FONT_HERSHEY_SIMPLEX


def grid_frames(grid: LatentGrid, cell: int = 128, margin: float = 0.08) -> Iterator[np.ndarray]:
    """Draw the grid, one [H, W, 3] uint8 RGB frame per time step.

    All cells share one framing (the box around every pose of every cell), so the sizes and places of the
    figures compare across cells. Rows are labelled with the row attribute's weight of B, columns with the
    column attribute's; the title names the kept attribute.

    Args:
        grid: from :func:`interpolate_grid`.
        cell: side of a cell in pixels.
        margin: empty share of a cell on each side.

    Yields:
        frames of ``(left + S * cell) x (top + S * cell)`` pixels.
    """
    steps, _, length = grid.poses.shape[:3]
    left, top = max(56, cell // 2), max(48, cell // 3)
    size = (left + steps * cell, top + steps * cell)
    lo = grid.poses.reshape(-1, 2).min(axis=0)
    hi = grid.poses.reshape(-1, 2).max(axis=0)
    scale = cell * (1 - 2 * margin) / max(float((hi - lo).max()), 1e-6)
    centre = (lo + hi) / 2
    background = _labelled_background(grid, size, left, top, cell)
    thickness = max(1, round(cell / 64))
    for t in range(length):
        frame = background.copy()
        for i in range(steps):
            for j in range(steps):
                origin = np.array([left + (j + 0.5) * cell, top + (i + 0.5) * cell])
                draw_pose(frame, (grid.poses[i, j, t] - centre) * scale + origin, LAYOUT, thickness=thickness)
        yield frame


def _labelled_background(grid: LatentGrid, size: tuple[int, int], left: int, top: int, cell: int) -> np.ndarray:
    """The frame without figures: cell borders, the title and the weights along both axes."""
    a, b = grid.names
    steps = len(grid.weights)
    frame = blank_canvas(*size)
    font = max(0.32, cell / 300)
    for k in range(steps + 1):
        cv2.line(frame, (left + k * cell, top), (left + k * cell, size[1] - 1), _GRID_LINE, 1)
        cv2.line(frame, (left, top + k * cell), (size[0] - 1, top + k * cell), _GRID_LINE, 1)
    title = f"{grid.rows} (down) x {grid.cols} (across): {a} -> {b};  {grid.kept} of {a}"
    cv2.putText(frame, title, (6, int(top * 0.42)), _FONT, font, _TEXT, 1, cv2.LINE_AA)
    for k, w in enumerate(grid.weights):
        cv2.putText(frame, f"{grid.cols} {w:.2f}", (left + k * cell + 4, top - 6), _FONT, font, _TEXT, 1, cv2.LINE_AA)
        cv2.putText(frame, grid.rows, (4, top + k * cell + cell // 2 - 4), _FONT, font, _TEXT, 1, cv2.LINE_AA)
        cv2.putText(frame, f"{w:.2f}", (4, top + k * cell + cell // 2 + int(16 * font / 0.4)), _FONT, font, _TEXT,
                    1, cv2.LINE_AA)
    return frame
