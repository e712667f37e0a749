"""Logging set-up and roadgaze's output convention.

Every command writes its records and results to stdout (or to files) and everything else, i.e.
progress bars, logs, warnings and the "wrote FILE" lines, to stderr. Log lines go through
`tqdm.write`, which takes a progress bar off the terminal, writes the line and draws the bar
again, so a log line never lands in the middle of a bar. Each event is told once.
"""

from __future__ import annotations

import json
import logging
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

_STANDARD_ATTRIBUTES = set(logging.makeLogRecord({}).__dict__) | {"message", "asctime"}

log = logging.getLogger("roadgaze")


class JsonFormatter(logging.Formatter):
    """One JSON object per record: time, level, logger, message and any `extra=` fields."""

    def format(self, record: logging.LogRecord) -> str:
        entry: dict[str, Any] = {
            "time": time.strftime("%Y-%m-%dT%H:%M:%S", time.gmtime(record.created))
            + f".{int(record.msecs):03d}Z",
            "level": record.levelname,
            "logger": record.name,
            "message": record.getMessage(),
        }
        for key, value in record.__dict__.items():
            if key not in _STANDARD_ATTRIBUTES:
                entry[key] = value
        if record.exc_info:
            entry["exception"] = self.formatException(record.exc_info)
        return json.dumps(entry, default=str)


class ProgressAwareHandler(logging.Handler):
    """Writes each record to the current `sys.stderr` through `tqdm.write`, so progress bars on
    stderr are cleared first and redrawn after the line."""

    def emit(self, record: logging.LogRecord) -> None:
        try:
            from tqdm import tqdm

            tqdm.write(self.format(record), file=sys.stderr)
        except Exception:
            self.handleError(record)


def setup_logging(level: str | None = None, json_format: bool = False) -> None:
    """Send roadgaze's logs to stderr; idempotent, so tests may call it repeatedly."""
    handler = ProgressAwareHandler()
    if json_format:
        handler.setFormatter(JsonFormatter())
    else:
        handler.setFormatter(logging.Formatter("%(asctime)s %(levelname)s %(name)s: %(message)s"))
    root = logging.getLogger("roadgaze")
    root.handlers[:] = [handler]
    root.setLevel(level or "INFO")
    root.propagate = False


def log_written(path: str | Path) -> None:
    """The one "wrote FILE" line of a command's output file (stderr, through the log)."""
    log.info("wrote %s", path)


@contextmanager
def records_dropped(logger: str, predicate: Callable[[logging.LogRecord], bool]) -> Iterator[None]:
    """Within the block, records of `logger` for which `predicate` is true are not logged (an
    event another line of the same command already tells)."""
    target = logging.getLogger(logger)

    def keep(record: logging.LogRecord) -> bool:
        return not predicate(record)

    target.addFilter(keep)
    try:
        yield
    finally:
        target.removeFilter(keep)
