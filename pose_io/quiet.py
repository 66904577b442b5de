"""Keep the log lines that native libraries print (MediaPipe, TensorFlow Lite, absl/glog) off the terminal.

MediaPipe's C++ graph writes straight to file descriptor 2 (``W0000 00:00:... inference_feedback_manager.cc:114]
...``, ``INFO: Created TensorFlow Lite XNNPACK delegate for CPU.``); no Python setting reaches it. While
:func:`quiet_native_logs` is open, descriptor 2 goes to a temporary file and Python's ``sys.stderr`` to a copy of
the real one, so a progress bar (rich writes to ``sys.stderr``) still draws. When it closes, the captured lines
that are not such third-party logging are written back to the terminal, so a real error is not lost; the rest go to
this module's debug log (``clone -v`` shows them).
"""

from __future__ import annotations

import logging
import os
import re
import sys
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager

log = logging.getLogger(__name__)

# absl/glog ("W0000 00:00:1796.. 13407 file.cc:114] ..."), TFLite's own ("INFO: Created TensorFlow Lite ..."),
# absl's notice before its logging starts, and the GL context lines MediaPipe prints on some machines.
THIRD_PARTY_LINE = re.compile(
    r"^(?:[IWEF]\d{4} \d\d:\d\d:\d+\.\d+\s+\d+ \S+:\d+\]"
    r"|INFO: Created TensorFlow Lite"
    r"|INFO: Initialized TensorFlow Lite"
    r"|WARNING: All log messages before absl::InitializeLog\(\) is called are written to STDERR"
    r"|gl_context|GL version:)"
)


def is_third_party(line: str) -> bool:
    """Whether ``line`` is native libraries' own logging (dropped), not a message for the user."""
    return bool(THIRD_PARTY_LINE.match(line))


@contextmanager
def quiet_native_logs() -> Iterator[None]:
    """Capture file descriptor 2 for the block; write back what is not third-party logging when it ends.

    Nesting is safe (the inner block captures into the outer one's file). Where descriptor 2 cannot be
    duplicated (no such descriptor), the block runs unchanged.
    """
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (OSError, ValueError, AttributeError):
        yield
        return
    python_stderr = sys.stderr
    with tempfile.TemporaryFile() as sink:
        terminal = os.fdopen(os.dup(saved), "w", buffering=1, encoding=getattr(python_stderr, "encoding", None)
                             or "utf-8", errors="replace")
        os.dup2(sink.fileno(), 2)
        sys.stderr = terminal
        try:
            yield
        finally:
            try:
                terminal.flush()
                python_stderr.flush()
            except (OSError, ValueError):
                pass
            sys.stderr = python_stderr
            os.dup2(saved, 2)
            os.close(saved)
            terminal.close()
            sink.seek(0)
            text = sink.read().decode("utf-8", errors="replace")
            kept = []
            for line in text.splitlines():
                if is_third_party(line):
                    log.debug("native: %s", line)
                elif line.strip():
                    kept.append(line)
            if kept:
                python_stderr.write("\n".join(kept) + "\n")
                python_stderr.flush()
