"""pose_io.errors: the one exception type for problems a user can cause."""

from __future__ import annotations

import pytest

import pose_io
from pose_io.errors import InputError


def test_input_error_is_a_value_error():
    # Callers that catch ValueError (argument checks) also catch bad user input.
    assert issubclass(InputError, ValueError)
    with pytest.raises(ValueError, match="poses.json: no frames"):
        raise InputError("poses.json: no frames")


def test_one_type_across_the_package(tmp_path):
    assert pose_io.InputError is InputError
    with pytest.raises(InputError) as info:
        pose_io.read_track(tmp_path / "missing")
    message = str(info.value)
    assert "missing" in message and "\n" not in message  # one line, naming the input
