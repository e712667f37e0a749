"""MediaPipe's own log lines on fd 2: start-up noise dropped, everything else passed on."""

from __future__ import annotations

import contextlib
import os
import sys
import tempfile
from collections.abc import Iterator

_NATIVE_NOISE = (
    "WARNING: Logging before InitGoogle()",
    "INFO: Created TensorFlow Lite",
    "INFO: [",
    "W0000 ",
    "I0000 ",
)
"""Start-up and shut-down lines of MediaPipe and LiteRT (its runtime) that say nothing to a user."""


@contextlib.contextmanager
def filtered_native_stderr() -> Iterator[None]:
    """Drop MediaPipe's start-up log lines (written by C++ to fd 2); pass every other line on."""
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (OSError, ValueError):
        yield
        return
    with tempfile.TemporaryFile(mode="w+b") as capture:
        os.dup2(capture.fileno(), 2)
        try:
            yield
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            capture.seek(0)
            kept = [
                line
                for line in capture.read().decode("utf-8", "replace").splitlines(keepends=True)
                if not line.startswith(_NATIVE_NOISE)
            ]
            if kept:
                sys.stderr.write("".join(kept))
                sys.stderr.flush()
