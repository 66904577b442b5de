"""Limits on what pose data may claim (pose_io.limits): coordinates, outliers, sizes, frame rates, lengths."""

from __future__ import annotations

import json
import logging
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

from pose_io import BODY25, InputError, PoseTrack, read_track, read_track_summary, write_track
from pose_io.clean import drop_outlier_joints, smooth
from pose_io.limits import MAX_IMAGE_SIDE, outlier_mask
from pose_io.read_json import SIDECAR_NAME
from pose_io.readers import parse_size
from pose_io.resample import resample

R_WRIST = BODY25.index("r_wrist")
L_WRIST = BODY25.index("l_wrist")
R_ANKLE = BODY25.index("r_ankle")


def with_joint(track: PoseTrack, t: int, j: int, xy: tuple[float, float]) -> np.ndarray:
    joints = track.joints.astype(np.float64)  # a copy
    joints[t, j] = xy
    return joints


def save_npz(path: Path, joints: np.ndarray, conf: np.ndarray, size=(640, 480), fps=30.0, **extra) -> Path:
    np.savez(path, joints=joints, confidence=conf, fps=fps, image_size=np.array(size), layout="body25", **extra)
    return path


def outlier_records(caplog) -> list[logging.LogRecord]:
    return [r for r in caplog.records if "outlier" in r.getMessage()]


# ----------------------------------------------------------------------------------------------- outliers


def test_wrist_at_1e6_is_dropped_with_one_warning_counting_them(tmp_path, walking_track, caplog):
    joints = with_joint(walking_track, 5, R_WRIST, (1e6, 240.0))
    joints[7, L_WRIST] = (300.0, -1e6)
    path = save_npz(tmp_path / "a.npz", joints, walking_track.confidence)
    with caplog.at_level(logging.WARNING):
        summary = read_track_summary(path)
    track = summary.track
    assert track.missing[5, R_WRIST] and track.missing[7, L_WRIST] and track.missing.sum() == 2
    assert summary.outliers == 2
    records = outlier_records(caplog)
    assert len(records) == 1 and "dropped 2 outlier joints" in records[0].getMessage()
    assert "r_wrist at frame 5" in records[0].getMessage() and str(path) in records[0].getMessage()
    np.testing.assert_array_equal(track.joints[~track.missing], walking_track.joints[~track.missing])


def test_off_frame_foot_a_bit_outside_the_image_is_kept(tmp_path, walking_track, caplog):
    joints = walking_track.joints.astype(np.float64)
    joints[:, R_ANKLE, 1] = 480 + 150  # 150 px below a 480-high frame (and the body reaches down to ~400)
    joints[:, R_WRIST, 0] = -200  # and a hand off the left edge
    with caplog.at_level(logging.WARNING):
        track = read_track(save_npz(tmp_path / "a.npz", joints, walking_track.confidence))
    assert not track.missing.any() and not outlier_records(caplog)


def test_both_rules_must_hold(walking_track):
    """Dropped only when > 1 image size (640 px) outside the image AND > 4 body sizes from the body."""
    size = walking_track.image_size
    # The walking body: ~310 px tall, body size (3 x median joint distance from the median joint) ~420 px.
    for x, dropped in [(1500.0, False),  # 860 px right of the image: outside the margin, but near the body
                       (3000.0, True)]:  # 2360 px right: far from the image and the body
        joints = with_joint(walking_track, 0, R_WRIST, (x, 240.0))
        assert outlier_mask(joints, size)[0, R_WRIST] == dropped, x
    small = walking_track.joints.astype(np.float64) * 0.1 + 200  # a body ~31 px tall: 1,000 px is 30 bodies
    for x, dropped in [(1200.0, False),  # far from the body but within 1 image size of the image
                       (1400.0, True)]:  # beyond 640 + 640
        joints = small.copy()
        joints[0, R_WRIST] = (x, 220.0)
        assert outlier_mask(joints, size)[0, R_WRIST] == dropped, x


def test_pose_with_few_joints_is_judged_by_the_image_alone(walking_track):
    joints = np.full_like(walking_track.joints, np.nan, dtype=np.float64)
    joints[0, [0, 1]] = [(300.0, 100.0), (5000.0, 100.0)]  # two joints: no body to measure
    mask = outlier_mask(joints, walking_track.image_size)
    assert mask[0].tolist().count(True) == 1 and mask[0, 1]


def test_unknown_image_size_measures_against_the_data(tmp_path, walking_track, caplog):
    from tests.pose_io.test_readers import write_frame

    for t in range(4):
        xyc = np.c_[walking_track.joints[t], walking_track.confidence[t]]
        if t == 2:
            xyc[R_WRIST, 0] = 1e30
        write_frame(tmp_path / "op", t, [xyc.ravel().tolist()])
    with caplog.at_level(logging.WARNING):
        summary = read_track_summary(tmp_path / "op")
    assert summary.size_source == "inferred" and summary.track.image_size == (384, 416)
    assert summary.track.missing[2, R_WRIST] and len(outlier_records(caplog)) == 1


def test_a_body_far_outside_the_image_is_an_error_not_silently_dropped(tmp_path, walking_track):
    far = walking_track.joints.astype(np.float64) + 1e30
    with pytest.raises(InputError, match=r"more than 16 image sizes outside the 640x480 image") as info:
        read_track(save_npz(tmp_path / "a.npz", far, walking_track.confidence))
    assert str(tmp_path / "a.npz") in str(info.value)
    no_size = tmp_path / "b.npy"
    np.save(no_size, walking_track.joints.astype(np.float64) + 30000)
    with pytest.raises(InputError, match="beyond the largest allowed image"):
        read_track(no_size)


def test_tracks_made_in_code_drop_outliers_on_request(walking_track):
    track = walking_track.replace(joints=with_joint(walking_track, 3, R_WRIST, (9000.0, 100.0)))
    clean, dropped = drop_outlier_joints(track)
    assert dropped.count == 1 and dropped.frame == 3 and dropped.joint == "r_wrist"
    assert clean.missing[3, R_WRIST] and clean.missing.sum() == 1
    assert drop_outlier_joints(walking_track)[0] is walking_track


# ----------------------------------------------------------------------------------------------- values


@pytest.mark.parametrize(
    "joints, message",
    [
        (np.full((2, 25, 2), 1 + 1j), "must hold real numbers, got dtype complex128"),
        (np.full((2, 25, 2), "1", dtype=object), "must hold real numbers, got dtype object"),
        (np.full((2, 25, 2), 1e39), "beyond float32 range"),
        (np.full((2, 25, 2), -np.inf), "infinite"),
        (np.full((2, 25, 2), 640 * 17 + 700.0), "more than 16 image sizes outside"),
    ],
)
def test_constructor_refuses_values_it_cannot_hold(joints, message):
    with pytest.raises(InputError, match=message):
        PoseTrack(joints, np.ones((2, 25)), 30.0, (640, 480), "body25")


@pytest.mark.parametrize(
    "fps, size, message",
    [
        (1e9, (640, 480), "fps 1e\\+09: must be from 0.01 to 1000"),
        (0.0, (640, 480), "fps 0: must be from"),
        (float("nan"), (640, 480), "fps nan"),
        (30.0, (100_000, 100_000), "image size 100000x100000: each side must be a whole number from 1 to 16384"),
        (30.0, (float("inf"), 4), "image size infx4"),
        (30.0, (640.5, 480), "image size 640.5x480"),
        (30.0, (10**400, 4), "image size >1e308x4"),
    ],
)
def test_constructor_limits_fps_and_size(walking_track, fps, size, message):
    with pytest.raises(InputError, match=message):
        PoseTrack(walking_track.joints, walking_track.confidence, fps, size, "body25")


def test_joint_values_beyond_float32_are_errors_not_missing(tmp_path, walking_track):
    path = save_npz(tmp_path / "a.npz", with_joint(walking_track, 1, 0, (1e39, 2.0)), walking_track.confidence)
    with pytest.raises(InputError, match=r"a.npz: joints: value 1e\+39 is beyond float32 range"):
        read_track(path)
    complex_path = save_npz(tmp_path / "c.npz", walking_track.joints.astype(np.complex64), walking_track.confidence)
    with pytest.raises(InputError, match="c.npz: joints: must hold real numbers, got dtype complex64"):
        read_track(complex_path)


# ----------------------------------------------------------------------------------------------- sizes, fps, lengths


def test_size_option_and_stored_sizes_share_one_limit(tmp_path, walking_track):
    assert parse_size("16384x16384") == (MAX_IMAGE_SIDE, MAX_IMAGE_SIDE)
    for text in ("16385x16", "100000x100000", "9" * 30 + "x9", "0x10"):
        with pytest.raises(InputError, match="each side must be a whole number from 1 to 16384 pixels"):
            parse_size(text)
    with pytest.raises(InputError, match="a.npz: image_size 100000x100000"):
        read_track(save_npz(tmp_path / "a.npz", walking_track.joints, walking_track.confidence, size=(100_000, 100_000)))
    folder = write_track(walking_track, tmp_path / "op")
    sidecar = json.loads((folder / SIDECAR_NAME).read_text())
    for key, value, message in [("image_size", [100_000, 100_000], "image_size 100000x100000"),
                                ("fps", 1e9, "fps 1e\\+09"), ("fps", 10**400, "fps >1e308")]:
        (folder / SIDECAR_NAME).write_text(json.dumps({**sidecar, key: value}))
        with pytest.raises(InputError, match=f"{SIDECAR_NAME}: {message}"):
            read_track(folder)
    csv_path = write_track(walking_track, tmp_path / "b.csv")
    csv_path.write_text(csv_path.read_text().replace("# image_size: 640x480", "# image_size: 20000x20000"))
    with pytest.raises(InputError, match="b.csv: image_size 20000x20000"):
        read_track(tmp_path / "b.csv")


def test_resampling_checks_before_allocating(walking_track):
    with pytest.raises(InputError, match="resampling fps 1e\\+09"):
        resample(walking_track, 1e9)
    slow = walking_track.replace(fps=0.01)
    tracemalloc.start()
    try:
        with pytest.raises(InputError, match="3,900,001 frames; at most 1,000,000"):
            resample(slow, 1000.0)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 1_000_000, peak
    assert resample(walking_track, 1000.0).num_frames == 1301


def test_huge_smoothing_sigma_does_not_allocate_a_huge_kernel(walking_track):
    tracemalloc.start()
    try:
        out = smooth(walking_track, 1e12)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 5_000_000 and out.num_frames == walking_track.num_frames
    # A flat kernel: every frame becomes the confidence-weighted mean of the whole track.
    np.testing.assert_allclose(out.joints[0], out.joints[-1], atol=1e-3)


# ----------------------------------------------------------------------------------------------- unreadable files


def test_unreadable_file_in_an_openpose_folder_is_named(tmp_path, walking_track, monkeypatch):
    folder = write_track(walking_track, tmp_path / "op")
    bad = folder / "op_000000000003_keypoints.json"
    real = Path.read_bytes

    def refuse(self: Path) -> bytes:
        if self == bad:
            raise PermissionError(13, "Permission denied", str(self))
        return real(self)

    monkeypatch.setattr(Path, "read_bytes", refuse)
    with pytest.raises(InputError, match=f"{bad}: cannot read \\(Permission denied\\)") as info:
        read_track(folder)
    assert "\n" not in str(info.value)
    monkeypatch.undo()
    bad.unlink()
    bad.mkdir()  # a folder where a frame file should be
    with pytest.raises(InputError, match=f"{bad}: cannot read \\(a folder\\)"):
        read_track(folder)
    bad.rmdir()
    bad.symlink_to(tmp_path / "nowhere")
    with pytest.raises(InputError, match=f"{bad}: cannot read \\(missing\\)"):
        read_track(folder)
    bad.unlink()
    bad.write_bytes(b"\xff\xfe{\x00")
    with pytest.raises(InputError, match=f"{bad}: not valid JSON"):
        read_track(folder)


def _png_header_only(width: int, height: int) -> bytes:
    """A tiny PNG whose header claims ``width`` x ``height`` (a decompression bomb's first bytes)."""
    import struct
    import zlib

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(b"\0" * 64)) + chunk(b"IEND", b"")


def test_background_images_are_sized_from_their_header_before_decoding(tmp_path):
    from pose_io.video import read_frames

    (tmp_path / "wide.png").write_bytes(_png_header_only(20_000, 20))
    (tmp_path / "bomb.png").write_bytes(_png_header_only(30_000, 30_000))
    tracemalloc.start()
    try:
        with pytest.raises(InputError, match="wide.png: image size 20000x20: each side"):
            read_frames(tmp_path / "wide.png")
        with pytest.raises(InputError, match="bomb.png: image too large to decode"):
            read_frames(tmp_path / "bomb.png")
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 5_000_000, peak
