"""clone.model.reference: one file holds the reference model; save -> load round trips; bad files, one clear error."""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
import pytest
import torch

from clone.model.canvas import Canvas
from clone.model.networks import GeneratorConfig, build_generator
from clone.model.reference import (
    FORMAT_VERSION,
    KIND,
    ReferenceModel,
    file_sha256,
    load_checkpoint_dict,
    load_reference_model,
    preview_path,
    save_reference_model,
)
from pose_io import InputError, PoseTrack
from retarget.baselines.global_scale import ScaleStats

CONFIG = GeneratorConfig(base_channels=4, depth=2, max_channels=8)


def _model(**changes: object) -> ReferenceModel:
    torch.manual_seed(0)
    net = build_generator("unet", CONFIG)
    rng = np.random.default_rng(0)
    joints = rng.uniform(0, 60, (5, 15, 2)).astype(np.float32)
    joints[2, 3] = np.nan
    conf = np.where(np.isnan(joints[..., 0]), 0.0, 0.8).astype(np.float32)
    fields = {
        "generator_name": "unet",
        "generator_config": CONFIG,
        "generator_state": net.state_dict(),
        "canvas": Canvas(x0=-4, y0=2, side=64, size=16, image_size=(80, 60)),
        "scale_stats": ScaleStats(10.0, 50.0, 30.0, 45.0, 40.0, 48.0),
        "reference_track": PoseTrack(joints, conf, 24.0, (80, 60), "body15"),
        "track_summary": {"frames": 5, "bones": np.array([1.5, 2.5]), "nested": {"visible": np.float32(0.75)}},
        "reference_codes": {"body": np.arange(4, dtype=np.float32), "placement": np.array([100.0, 40.0, 55.0])},
        "codes_weights": "ab" * 32,
        "codes_weights_path": "/somewhere/weights.pt",
        "training": {"steps": 7, "config": {"lr": 2e-4}, "trainer": {"step": torch.tensor(7)}},
        "temporal": True,
    }
    fields.update(changes)
    return ReferenceModel(**fields)


def _same_outputs(a: ReferenceModel, b: ReferenceModel) -> None:
    x = torch.rand(1, CONFIG.in_channels, 16, 16)
    with torch.no_grad():
        torch.testing.assert_close(a.build_generator()(x), b.build_generator()(x), rtol=0, atol=0)


def test_save_load_round_trip(tmp_path):
    model = _model()
    path = save_reference_model(model, tmp_path / "ref.pt")
    assert path == tmp_path / "ref.pt" and sorted(p.name for p in tmp_path.iterdir()) == ["ref.pt"]
    back = load_reference_model(path)
    assert back.generator_name == "unet" and back.generator_config == CONFIG
    assert back.canvas == model.canvas and back.scale_stats == model.scale_stats
    assert back.reference_track.equals(model.reference_track)
    assert back.reference_track.fps == 24.0 and back.reference_track.image_size == (80, 60)
    # numpy values come back as numpy arrays; plain data stays plain.
    assert back.track_summary["frames"] == 5 and back.track_summary["nested"]["visible"] == 0.75
    np.testing.assert_array_equal(back.track_summary["bones"], [1.5, 2.5])
    np.testing.assert_array_equal(back.reference_codes["body"], np.arange(4))
    assert back.reference_codes["body"].dtype == np.float32
    assert back.codes_weights == "ab" * 32 and back.codes_weights_path == "/somewhere/weights.pt"
    assert back.training["steps"] == 7 and int(back.training["trainer"]["step"]) == 7
    assert back.temporal is True
    _same_outputs(model, back)


def test_the_file_is_a_plain_versioned_dict(tmp_path):
    save_reference_model(_model(), tmp_path / "ref.pt")
    data = torch.load(tmp_path / "ref.pt", map_location="cpu", weights_only=True)
    assert data["kind"] == KIND and data["format_version"] == FORMAT_VERSION
    assert not any(k.startswith(("module.", "_orig_mod.")) for k in data["generator"]["state_dict"])
    assert load_checkpoint_dict(tmp_path / "ref.pt", KIND)["generator"]["name"] == "unet"
    with pytest.raises(InputError, match="not a clone2d clone2d-retarget file \\(kind 'clone2d-reference'\\)"):
        load_checkpoint_dict(tmp_path / "ref.pt", "clone2d-retarget")


def test_optional_entries_may_be_absent(tmp_path):
    model = _model(scale_stats=None, reference_codes=None, codes_weights=None, codes_weights_path=None,
                   training=None, temporal=False)
    back = load_reference_model(save_reference_model(model, tmp_path / "ref.pt"))
    assert back.scale_stats is None and back.reference_codes is None and back.training is None
    assert back.codes_weights is None and back.temporal is False
    data = torch.load(tmp_path / "ref.pt", weights_only=True)
    assert "training" not in data


def test_existing_file_is_kept_unless_overwrite(tmp_path):
    path = tmp_path / "ref.pt"
    path.write_bytes(b"mine")
    with pytest.raises(InputError, match="already exists"):
        save_reference_model(_model(), path, overwrite=False)
    assert path.read_bytes() == b"mine"
    save_reference_model(_model(), path)  # overwrite is the default: a run rewrites its own file
    assert load_reference_model(path).generator_name == "unet"


def test_build_generator_is_in_eval_mode_on_the_device():
    net = _model().build_generator("cpu")
    assert not net.training and next(net.parameters()).device == torch.device("cpu")


def test_bad_files_are_one_clear_error(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        load_reference_model(tmp_path / "none.pt")
    (tmp_path / "text.pt").write_text("not a torch file")
    with pytest.raises(InputError, match="text.pt: not a readable clone2d clone2d-reference file"):
        load_reference_model(tmp_path / "text.pt")
    torch.save({"kind": "clone2d-retarget", "format_version": 1}, tmp_path / "other.pt")
    with pytest.raises(InputError, match="not a clone2d clone2d-reference file \\(kind 'clone2d-retarget'\\)"):
        load_reference_model(tmp_path / "other.pt")
    torch.save([1, 2], tmp_path / "list.pt")
    with pytest.raises(InputError, match="kind 'list'"):
        load_reference_model(tmp_path / "list.pt")


@pytest.mark.parametrize("version", [FORMAT_VERSION + 1, 0, "2"])
def test_unknown_format_versions_are_refused(tmp_path, version):
    path = save_reference_model(_model(), tmp_path / "ref.pt")
    data = torch.load(path, weights_only=True)
    data["format_version"] = version
    torch.save(data, path)
    with pytest.raises(InputError, match=f"format version {version!r} is not supported.*up to {FORMAT_VERSION}"):
        load_reference_model(path)


def test_format_1_files_still_load(tmp_path):
    path = save_reference_model(_model(training={"steps": 3, "seconds": 1.0}), tmp_path / "ref.pt")
    data = torch.load(path, weights_only=True)
    data["format_version"] = 1
    torch.save(data, path)
    assert load_reference_model(path).training == {"steps": 3, "seconds": 1.0}


def test_weights_that_do_not_fit_the_config_are_a_damaged_model(tmp_path):
    path = save_reference_model(_model(), tmp_path / "ref.pt")
    data = torch.load(path, weights_only=True)
    data["generator"]["config"]["base_channels"] = 8
    torch.save(data, path)
    with pytest.raises(InputError, match="ref.pt: damaged reference model"):
        load_reference_model(path)
    del data["canvas"]
    torch.save(data, path)
    with pytest.raises(InputError, match="damaged reference model"):
        load_reference_model(path)
    data = torch.load(save_reference_model(_model(), path), weights_only=True)
    data["training"] = [1, 2]
    torch.save(data, path)
    with pytest.raises(InputError, match="damaged reference model \\(training entry is a list"):
        load_reference_model(path)


def test_file_sha256_and_preview_path(tmp_path):
    blob = bytes(range(256)) * 5000  # more than one read chunk
    (tmp_path / "w.pt").write_bytes(blob)
    assert file_sha256(tmp_path / "w.pt") == hashlib.sha256(blob).hexdigest()
    assert preview_path(tmp_path / "models" / "ref.pt") == tmp_path / "models" / "ref.preview.png"
    assert preview_path("runs/a.b.pt") == Path("runs/a.b.preview.png")


PLATE_CONFIG = GeneratorConfig(base_channels=4, depth=2, max_channels=8, alpha=True)


def _plate_model(**changes: object) -> ReferenceModel:
    torch.manual_seed(0)
    plate = np.random.default_rng(1).integers(0, 256, (16, 16, 3), dtype=np.uint8)
    fields = {"generator_config": PLATE_CONFIG, "generator_state": build_generator("unet", PLATE_CONFIG).state_dict(),
              "plate": plate}
    fields.update(changes)
    return _model(**fields)


def test_background_plate_round_trip(tmp_path):
    model = _plate_model()
    back = load_reference_model(save_reference_model(model, tmp_path / "ref.pt"))
    assert back.generator_config == PLATE_CONFIG and back.plate.dtype == np.uint8
    np.testing.assert_array_equal(back.plate, model.plate)
    plate = back.plate_tensor()
    assert plate.shape == (1, 3, 16, 16) and plate.min() >= -1 and plate.max() <= 1
    x = torch.rand(1, CONFIG.in_channels, 16, 16)
    with torch.no_grad():
        torch.testing.assert_close(model.build_generator()(x, model.plate_tensor()), back.build_generator()(x, plate),
                                   rtol=0, atol=0)
    assert _model().plate is None and _model().plate_tensor() is None


def test_format_2_files_load_and_run_without_a_plate(tmp_path):
    path = save_reference_model(_model(), tmp_path / "ref.pt")
    data = torch.load(path, weights_only=True)
    data["format_version"] = 2
    del data["background"]  # version 2 had no such entry
    torch.save(data, path)
    back = load_reference_model(path)
    assert back.plate is None and not back.generator_config.uses_plate
    _same_outputs(_model(), back)


def test_a_missing_or_wrong_plate_is_a_damaged_model(tmp_path):
    path = save_reference_model(_plate_model(), tmp_path / "ref.pt")
    data = torch.load(path, weights_only=True)
    for background, message in ((None, "holds none"), ({"plate": torch.zeros(8, 8, 3, dtype=torch.uint8)}, "8, 8, 3"),
                                ({"plate": torch.zeros(16, 16, 3)}, "float32"), ([1], "not a dict")):
        torch.save({**data, "background": background}, path)
        with pytest.raises(InputError, match=f"damaged reference model \\(.*{message}"):
            load_reference_model(path)


def test_pose_layout_round_trip_and_files_before_it_draw_body15(tmp_path):
    assert _model().pose_layout == "body15"
    back = load_reference_model(save_reference_model(_model(pose_layout="body31"), tmp_path / "ref.pt"))
    assert back.pose_layout == "body31"
    path = save_reference_model(_model(), tmp_path / "old.pt")
    data = torch.load(path, weights_only=True)
    del data["pose_layout"]  # files before detailed pose maps had no such entry
    torch.save(data, path)
    assert load_reference_model(path).pose_layout == "body15"
    torch.save({**data, "pose_layout": "smpl"}, path)
    with pytest.raises(InputError, match="damaged reference model \\(.*unknown layout 'smpl'"):
        load_reference_model(path)


def test_face_pass_round_trip_and_a_damaged_one_is_refused(tmp_path):
    from clone.model.face import build_face_pass, face_pass_config

    torch.manual_seed(3)
    net = build_face_pass()
    for p in net.parameters():  # something other than the zero start
        p.data.normal_(0.0, 0.1)
    entry = {"config": face_pass_config().to_dict(), "state_dict": net.state_dict(), "radius": 4.5}
    assert _model().face_pass is None and _model().build_face_pass() is None
    back = load_reference_model(save_reference_model(_model(face_pass=entry), tmp_path / "ref.pt"))
    passed = back.build_face_pass()
    assert passed.radius == 4.5
    x = torch.rand(1, 6, 64, 64)
    with torch.no_grad():
        torch.testing.assert_close(passed.net(x), net.eval()(x), rtol=0, atol=0)
    data = torch.load(tmp_path / "ref.pt", weights_only=True)
    for bad, message in (({**entry, "radius": -1.0}, "radius"), ({"config": entry["config"]}, "face_pass entry"),
                         ({**entry, "state_dict": {}}, "loading state_dict")):
        torch.save({**data, "face_pass": bad}, tmp_path / "bad.pt")
        with pytest.raises(InputError, match=f"damaged reference model \\(.*{message}"):
            load_reference_model(tmp_path / "bad.pt")
