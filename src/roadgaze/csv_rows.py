"""Reading a small CSV file with a header (a manifest, a speed track) into rows, or one error."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

from roadgaze.errors import RoadgazeError


def read_csv_rows(
    path: Path, error: type[RoadgazeError], what: str
) -> tuple[list[str], list[dict[str | None, Any]]]:
    """The header (names stripped) and the rows of a UTF-8 CSV file (a BOM is allowed), as
    `csv.DictReader` gives them (extra cells under the key None). Raises `error` naming `what`
    and the file when it cannot be read."""
    try:
        with path.open(newline="", encoding="utf-8-sig") as handle:
            reader = csv.DictReader(handle)
            header = [name.strip() for name in reader.fieldnames or []]
            rows: list[dict[str | None, Any]] = list(reader)
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise error(f"cannot read {what} {path}: {exc}") from None
    return header, rows
