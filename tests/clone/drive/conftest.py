"""Fixtures of the drive tests: a tiny reference model trained through the CLI."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from clone.cli.main import app
from tests.clone.train_ref.helpers import figure_track, train_args, write_reference


@pytest.fixture
def trained(tmp_path: Path) -> Path:
    """A 32² model trained 3 steps on a 24-frame figure (tests.clone.train_ref.helpers)."""
    poses, frames = write_reference(tmp_path / "ref", figure_track(24))
    out = tmp_path / "ref.pt"
    result = CliRunner().invoke(app, train_args(poses, frames, out))
    assert result.exit_code == 0, result.output
    return out
