"""A data set's `ground_truth.csv`: one labelled image per row."""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

from roadgaze.errors import DatasetError


@dataclass(frozen=True, slots=True)
class GroundTruth:
    """One labelled image of a data set."""

    file: str
    yaw_deg: float
    pitch_deg: float | None = None
    subject: str | None = None
    """Who is in the image, when the file has a `subject` column (for leave-half-out checks)."""


def load_ground_truth(dataset_dir: Path) -> tuple[list[GroundTruth], int]:
    """Rows of `<dataset_dir>/ground_truth.csv` and how many were skipped for |pitch| = 90.

    Raises `DatasetError` for a missing folder or file, missing columns, and missing, non-numeric
    or non-finite values.
    """
    csv_path = dataset_dir / "ground_truth.csv"
    if not dataset_dir.is_dir():
        raise DatasetError(f"{dataset_dir}: not a folder; pass a folder with ground_truth.csv")
    if not csv_path.is_file():
        raise DatasetError(f"{csv_path} not found; the folder needs a ground_truth.csv")
    rows: list[GroundTruth] = []
    skipped = 0
    try:
        with csv_path.open(newline="", encoding="utf-8") as stream:
            reader = csv.DictReader(stream)
            columns = set(reader.fieldnames or [])
            if not {"file", "yaw_deg"} <= columns:
                raise DatasetError(
                    f"{csv_path}: needs columns file,yaw_deg; found {','.join(sorted(columns))}"
                )
            for line, row in enumerate(reader, start=2):
                try:
                    yaw_deg = float(row["yaw_deg"])  # None (a short row) raises TypeError
                    pitch_text = (row.get("pitch_deg") or "").strip()
                    pitch_deg = float(pitch_text) if pitch_text else None
                    if not math.isfinite(yaw_deg) or not math.isfinite(pitch_deg or 0.0):
                        raise ValueError("not finite")
                except (TypeError, ValueError):
                    raise DatasetError(
                        f"{csv_path}:{line}: yaw_deg/pitch_deg must be numbers (finite), found "
                        f"{str(row.get('yaw_deg'))[:40]!r}/{str(row.get('pitch_deg'))[:40]!r}"
                    ) from None
                if not row.get("file"):
                    raise DatasetError(f"{csv_path}:{line}: empty file name")
                if pitch_deg is not None and abs(pitch_deg) == 90.0:
                    skipped += 1
                    continue
                subject = (row.get("subject") or "").strip() or None
                rows.append(GroundTruth(row["file"], yaw_deg, pitch_deg, subject))
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise DatasetError(f"cannot read {csv_path}: {exc}") from None
    if not rows:
        raise DatasetError(f"{csv_path}: no usable rows")
    return rows, skipped
