"""MediaPipe's own log lines on fd 2: start-up noise dropped, everything else passed on.

A native line that is kept goes through roadgaze's log (logger `roadgaze.native`, its level from
the glog letter: E0000 ... an error, W0000 ... a warning), so `--log-json` output stays one JSON
object per line. Lines of roadgaze's own log and progress bars written meanwhile by other threads
(they land on fd 2 too while it is captured) pass as they were.
"""

from __future__ import annotations

import contextlib
import logging
import os
import re
import sys
import tempfile
from collections.abc import Iterator

log = logging.getLogger("roadgaze.native")

_NATIVE_NOISE = (
    "WARNING: Logging before InitGoogle()",
    "INFO: Created TensorFlow Lite",
    "INFO: [",
    "W0000 ",
    "I0000 ",
)
"""Start-up and shut-down lines of MediaPipe and LiteRT (its runtime) that say nothing to a user."""

_OWN_LINE = re.compile(r"^(\{\"time\": |\d{4}-\d\d-\d\d \d\d:\d\d:\d\d,\d{3} [A-Z]+ )|\r")
"""A line of roadgaze's log (JSON or text format) or of a progress bar (redrawn with \\r)."""

_GLOG_LEVELS = {"F": logging.CRITICAL, "E": logging.ERROR, "W": logging.WARNING, "I": logging.INFO}


def _pass_on(lines: list[str]) -> None:
    """Roadgaze's own lines as they were; native ones as log records."""
    for line in lines:
        if _OWN_LINE.search(line):
            sys.stderr.write(line)
            sys.stderr.flush()
        elif line.strip():
            level = logging.WARNING
            if re.match(r"^[FEWI]\d{4} ", line):
                level = _GLOG_LEVELS[line[0]]
            elif line.startswith(("ERROR:", "WARNING:", "INFO:")):
                level = logging.getLevelName(line.split(":", 1)[0])
            log.log(level, "%s", line.rstrip("\n"))


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
            _pass_on(kept)
