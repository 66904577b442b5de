"""pose_io.errors: the one exception type for problems a user can cause; interrupts found inside other errors."""

from __future__ import annotations

import pytest

import pose_io
from pose_io.errors import InputError, raise_if_interrupted


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


def _wrapped(interrupt: BaseException, suppress: bool) -> Exception:
    """What an extension's import makes of a signal handled inside it: another error, chained to the interrupt."""
    try:
        try:
            raise interrupt
        except BaseException as inner:
            if suppress:
                raise ImportError("initialization failed") from None  # the chain hidden, the context kept
            raise ImportError("initialization failed") from inner
    except ImportError as outer:
        return outer


@pytest.mark.parametrize("suppress", [False, True])
@pytest.mark.parametrize("interrupt", [SystemExit(143), KeyboardInterrupt()])
def test_an_interrupt_inside_another_error_is_raised_again(interrupt, suppress):
    with pytest.raises(type(interrupt)) as raised:
        raise_if_interrupted(_wrapped(interrupt, suppress))
    assert raised.value is interrupt


def test_an_interrupt_behind_an_unrelated_cause_is_found():
    stop = SystemExit(143)
    try:
        try:
            raise stop
        except SystemExit:
            raise ImportError("initialization failed") from OSError("a cause set by the extension")
    except ImportError as outer:
        with pytest.raises(SystemExit) as raised:
            raise_if_interrupted(outer)  # the interrupt is only the context
    assert raised.value is stop


def test_ordinary_errors_are_left_to_the_caller():
    raise_if_interrupted(ImportError("no module named onnx"))  # nothing behind it
    raise_if_interrupted(_wrapped(SystemExit(0), suppress=False))  # a library's own exit, not a signal
    try:
        try:
            raise OSError("disk full")
        except OSError as inner:
            raise RuntimeError("export failed") from inner
    except RuntimeError as outer:
        raise_if_interrupted(outer)  # a chain without an interrupt
