"""Fixtures of the report tests."""

from __future__ import annotations

import numpy as np
import pytest

from pose_io import BODY15
from tests.clone.report.helpers import SIZE, T, walk


@pytest.fixture
def tiny_models(tmp_path):
    """A reference model with a tiny untrained generator on a 32² canvas of 64² frames, and tiny
    untrained retargeting weights: the run is real, the pictures are noise."""
    import torch

    from clone.model.canvas import full_frame_canvas
    from clone.model.networks import GeneratorConfig, build_generator
    from clone.model.reference import ReferenceModel, save_reference_model
    from retarget.baselines.global_scale import scale_stats
    from retarget.network.checkpoint import save_checkpoint
    from retarget.network.model import NetworkConfig, RetargetNet
    from retarget.network.preprocess import NormStats

    torch.manual_seed(0)
    reference = walk(T)
    config = GeneratorConfig(base_channels=4, depth=3, max_channels=8)
    net = build_generator("unet", config)
    model = ReferenceModel(
        generator_name="unet", generator_config=config, generator_state=net.state_dict(),
        canvas=full_frame_canvas((SIZE, SIZE), 32), scale_stats=scale_stats(reference.joints, BODY15),
        reference_track=reference, track_summary={},
    )  # fmt: skip
    model_path = save_reference_model(model, tmp_path / "ref.pt")
    small = NetworkConfig(motion_channels=(30, 16, 16, 16), body_channels=(28, 8, 8, 8),
                          view_channels=(28, 8, 8, 8), decoder_channels=(16, 16, 30))  # fmt: skip
    weights = save_checkpoint(tmp_path / "w.pt", RetargetNet(small).eval(),
                              NormStats(np.zeros((15, 2)), np.full((15, 2), 20.0)))  # fmt: skip
    return model_path, weights
