"""Small builders of the files a bad-input case starts with, each writing into the case's ``tmp_path``."""

from __future__ import annotations

import json
import shutil
from collections.abc import Callable
from pathlib import Path

import numpy as np

Builder = Callable[[Path], None]


def _figure(frames: int = 24):
    from tests.clone.train_ref.helpers import figure_track

    return figure_track(frames)


def poses_npz(tmp: Path) -> None:
    """A good 24-frame body15 track, ``poses.npz``."""
    from pose_io.writers import write_track

    write_track(_figure(), tmp / "poses.npz")


def poses_dir(tmp: Path) -> None:
    """The same track as an OpenPose folder ``poses/``."""
    from pose_io.writers import write_track

    write_track(_figure(), tmp / "poses")


def reference(tmp: Path) -> None:
    """A reference for train-ref: ``ref/poses`` (OpenPose) and ``ref/frames`` (PNGs)."""
    from tests.clone.train_ref.helpers import write_reference

    write_reference(tmp / "ref", _figure())


def bad_json_dir(tmp: Path) -> None:
    (tmp / "badjson").mkdir()
    (tmp / "badjson" / "000000_keypoints.json").write_text("{not json")


def wrong_json_dir(tmp: Path) -> None:
    (tmp / "wrongjson").mkdir()
    (tmp / "wrongjson" / "000000_keypoints.json").write_text(json.dumps({"people": "nobody"}))


def empty_dir(tmp: Path) -> None:
    (tmp / "empty").mkdir()


def bad_npz(tmp: Path) -> None:
    (tmp / "bad.npz").write_bytes(b"this is not a zip archive")


def wrong_npz(tmp: Path) -> None:
    np.savez(tmp / "wrong.npz", something=np.zeros(3))


def bad_csv(tmp: Path) -> None:
    (tmp / "bad.csv").write_text("a,b,c\n1,2\nx,y,z\n")


def empty_csv(tmp: Path) -> None:
    (tmp / "empty.csv").write_text("")


def huge_npz(tmp: Path) -> None:
    """A track whose coordinates are 1e30 (pose_io's limits)."""
    track = _figure()
    np.savez(tmp / "huge.npz", joints=np.full(track.joints.shape, 1e30, np.float32),
             confidence=track.confidence, fps=np.float32(25), image_size=np.array([96, 72]), layout="body15")


def empty_file(tmp: Path) -> None:
    (tmp / "empty.bin").write_bytes(b"")


def text_file(tmp: Path) -> None:
    (tmp / "notes.txt").write_text("not a pose file\n")


def garbage_pt(tmp: Path) -> None:
    (tmp / "garbage.pt").write_bytes(b"\x00\x01garbage" * 20)


def foreign_pt(tmp: Path) -> None:
    """A torch file of nobody's kind."""
    import torch

    torch.save({"weights": torch.zeros(2)}, tmp / "foreign.pt")


def retarget_pt(tmp: Path) -> None:
    """The shipped retargeting weights: a real model file, of the other kind."""
    from retarget.api import PACKAGED_WEIGHTS

    shutil.copy(PACKAGED_WEIGHTS, tmp / "retarget.pt")


def bad_motion(tmp: Path) -> None:
    (tmp / "bad.bvh").write_text("HIERARCHY\nROOT nothing {\n")


def old_mp4(tmp: Path) -> None:
    (tmp / "old.mp4").write_bytes(b"an earlier video")


def old_outputs(tmp: Path) -> None:
    """Outputs of an earlier run: a file of every kind and a folder."""
    for name in ("old.mp4", "old.npz", "old.csv", "old.json", "old.pt", "old.png", "old.preview.png"):
        (tmp / name).write_bytes(b"earlier " + name.encode())
    (tmp / "olddir").mkdir()
    (tmp / "olddir" / "keep.txt").write_text("keep me")


def a_folder(tmp: Path) -> None:
    (tmp / "folder.mp4").mkdir()
    (tmp / "folder.mp4" / "inside.txt").write_text("inside")
    (tmp / "dir").mkdir()


def file_parent(tmp: Path) -> None:
    """``blocker`` is a file, so ``blocker/x`` cannot be created."""
    (tmp / "blocker").write_text("a file where a folder would go")


def mocap_empty(tmp: Path) -> None:
    (tmp / "mocap").mkdir()


def bad_character(tmp: Path) -> None:
    (tmp / "character.json").write_text('{"name": "x", "legs": "long"')


def earlier_demo(tmp: Path) -> None:
    """A folder made by an earlier `clone demo`, with its report."""
    (tmp / "demo").mkdir()
    (tmp / "demo" / ".clone2d-demo").write_text("made by clone demo; `clone demo` replaces this folder\n")
    (tmp / "demo" / "report").mkdir()
    (tmp / "demo" / "report" / "report.html").write_text("<html>earlier report</html>")


def clips(tmp: Path) -> None:
    """``clips/``: two good driver tracks, ``a.npz`` and ``b.npz`` (a batch for `retarget apply`)."""
    from pose_io.writers import write_track

    (tmp / "clips").mkdir()
    write_track(_figure(), tmp / "clips" / "a.npz")
    write_track(_figure(30), tmp / "clips" / "b.npz")


def clips_bad(tmp: Path) -> None:
    """:func:`clips` and a corrupt ``clips/c.npz`` among them."""
    clips(tmp)
    (tmp / "clips" / "c.npz").write_bytes(b"this is not a zip archive")


def clips_clash(tmp: Path) -> None:
    """:func:`clips` and ``clips/a.csv``, whose output would be ``a.npz`` too."""
    from pose_io.writers import write_track

    clips(tmp)
    write_track(_figure(), tmp / "clips" / "a.csv")


def old_batch_output(tmp: Path) -> None:
    """``moved/b.npz``: the output of an earlier batch."""
    (tmp / "moved").mkdir()
    (tmp / "moved" / "b.npz").write_bytes(b"an earlier result")
