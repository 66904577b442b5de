"""Fixtures of the train-ref tests (defined in helpers so that the drive tests can use them too)."""

from tests.clone.train_ref.helpers import _restore_threads, reference  # noqa: F401 (fixtures)
