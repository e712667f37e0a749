"""Parquet tables of a drive (frames, alerts) and of the fleet, written atomically.

The Arrow schemas are derived from the typed descriptions in `roadgaze.outputs.records`
(`RECORD_SCHEMA`, `ALERT_SCHEMA`), with the drive's metadata in front, so a field added to the
flat record appears in the Parquet files without a change here. A file is written under a
temporary name in its own folder, flushed to disk and renamed: a crash leaves either the old file
or the new one, never half of one.
"""

from __future__ import annotations

import contextlib
import json
import os
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any, BinaryIO

import pyarrow as pa
import pyarrow.parquet as pq

from roadgaze.outputs import records
from roadgaze.outputs.records import FieldType

DRIVE_COLUMNS: tuple[tuple[str, Any], ...] = (
    ("drive_id", pa.string()),
    ("driver_id", pa.string()),
    ("vehicle_id", pa.string()),
    ("start_time", pa.timestamp("us", tz="UTC")),
)
"""The drive's metadata, repeated on every row of its frames and alerts tables."""

ARROW_TYPES: dict[FieldType, Any] = {
    FieldType.BOOL: pa.bool_(),
    FieldType.INT: pa.int64(),
    FieldType.FLOAT: pa.float64(),
    FieldType.STR: pa.string(),
    FieldType.STR_LIST: pa.list_(pa.string()),
    FieldType.HANDS: pa.list_(
        pa.struct(
            [
                ("side", pa.string()),
                ("side_score", pa.float64()),
                ("score", pa.float64()),
                ("landmarks_px", pa.list_(pa.list_(pa.float64(), 3))),
            ]
        )
    ),
}

METADATA_KEY = b"roadgaze.drive"
"""Parquet key-value metadata holding the drive's fingerprint and summary (JSON)."""

TEMPORARY_SUFFIX = ".tmp"
ROWS_PER_BATCH = 4096
"""Rows buffered before they go to the file (memory stays flat on long drives)."""


def arrow_schema(fields: Sequence[tuple[str, FieldType]]) -> Any:
    """The Arrow schema of a typed description; every column nullable."""
    return pa.schema([pa.field(name, ARROW_TYPES[field_type]) for name, field_type in fields])


def frames_schema() -> Any:
    """Drive metadata, then every field of the flat per-frame record."""
    drive = [pa.field(name, arrow_type) for name, arrow_type in DRIVE_COLUMNS]
    return pa.schema([*drive, *arrow_schema(records.RECORD_SCHEMA)])


def alerts_schema() -> Any:
    """Drive metadata, the frame the alert was raised on, then every field of the alert."""
    return pa.schema(
        [
            *(pa.field(n, t) for n, t in DRIVE_COLUMNS),
            pa.field("frame", pa.int64()),
            *arrow_schema(records.ALERT_SCHEMA),
        ]
    )


def temporary_path(path: Path) -> Path:
    """The name a file is written under before it is renamed to `path` (same folder, hidden)."""
    return path.with_name(f".{path.name}.{os.getpid()}{TEMPORARY_SUFFIX}")


def remove_temporary_files(folder: Path) -> int:
    """Delete files a killed run left under temporary names in `folder`; returns how many."""
    removed = 0
    for path in folder.glob(f".*{TEMPORARY_SUFFIX}"):
        path.unlink(missing_ok=True)
        removed += 1
    return removed


def fsync_folder(folder: Path) -> None:
    """Make a rename in `folder` durable (a no-op where folders cannot be opened)."""
    try:
        descriptor = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(descriptor)
    except OSError:
        pass
    finally:
        os.close(descriptor)


class AtomicParquetWriter:
    """Rows appended in batches to a temporary file; `commit()` renames it to `path`.

    `constant` columns (the drive's metadata) are filled in on every row. `discard()` (also on
    leaving a `with` block without a commit) deletes the temporary file.
    """

    def __init__(self, path: Path, schema: Any, constant: dict[str, Any]) -> None:
        self.path = path
        self.rows = 0
        self._schema = schema
        self._constant = constant
        self._columns: dict[str, list[Any]] = {name: [] for name in schema.names}
        self._buffered = 0
        self._temporary = temporary_path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        self._file = self._temporary.open("wb")
        self._writer: Any = pq.ParquetWriter(self._file, schema, compression="zstd")

    def append(self, fields: dict[str, Any]) -> None:
        """One row: `fields` by column name (columns it lacks are null), plus the constants."""
        row = {**fields, **self._constant}
        for name, column in self._columns.items():
            column.append(row.get(name))
        self._buffered += 1
        self.rows += 1
        if self._buffered >= ROWS_PER_BATCH:
            self._flush()

    def _flush(self) -> None:
        if self._buffered:
            batch = pa.RecordBatch.from_pydict(self._columns, schema=self._schema)
            self._writer.write_batch(batch)
            self._columns = {name: [] for name in self._columns}
            self._buffered = 0

    def commit(
        self, metadata: dict[str, Any], filled: Mapping[str, Sequence[float | None]] | None = None
    ) -> None:
        """Write the rest, store `metadata` (JSON) under `METADATA_KEY`, sync and rename.

        `filled` gives columns known only at the end (one value per row, e.g. the offline pass):
        the streamed file is then copied row group by row group with those columns replaced,
        so memory stays bounded by one row group.
        """
        self._flush()
        key_value = {METADATA_KEY: json.dumps(metadata).encode()}
        if filled:
            self._writer.close()
            self._writer = None
            self._file.close()
            final = self._temporary.with_name(self._temporary.name + ".filled" + TEMPORARY_SUFFIX)
            try:
                with final.open("wb") as handle:
                    _copy_filled(self._temporary, handle, self._schema, filled, key_value)
                    handle.flush()
                    os.fsync(handle.fileno())
                final.replace(self.path)
            finally:
                final.unlink(missing_ok=True)
                self._temporary.unlink(missing_ok=True)
        else:
            self._writer.add_key_value_metadata(key_value)
            self._writer.close()
            self._writer = None
            self._file.flush()
            os.fsync(self._file.fileno())
            self._file.close()
            self._temporary.replace(self.path)
        fsync_folder(self.path.parent)

    def discard(self) -> None:
        """Drop what was written; the file at `path`, if any, is left as it was."""
        if self._writer is not None:
            with contextlib.suppress(OSError, pa.ArrowException):
                self._writer.close()
            self._writer = None
        if not self._file.closed:
            self._file.close()
        self._temporary.unlink(missing_ok=True)

    def __enter__(self) -> AtomicParquetWriter:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.discard()


def _copy_filled(
    source: Path,
    handle: BinaryIO,
    schema: Any,
    filled: Mapping[str, Sequence[float | None]],
    key_value: dict[bytes, bytes],
) -> None:
    """`source` written to `handle` with the `filled` columns replaced, one row group at a time."""
    streamed = pq.ParquetFile(source)
    writer = pq.ParquetWriter(handle, schema, compression="zstd")
    try:
        start = 0
        for group in range(streamed.num_row_groups):
            table = streamed.read_row_group(group)
            end = start + table.num_rows
            for name, values in filled.items():
                index = schema.get_field_index(name)
                column = pa.array(values[start:end], type=schema.field(name).type)
                table = table.set_column(index, schema.field(name), column)
            writer.write_table(table)
            start = end
        writer.add_key_value_metadata(key_value)
    finally:
        writer.close()


def read_drive_metadata(path: Path) -> dict[str, Any] | None:
    """The metadata stored by `commit` in a Parquet file; None when the file is missing,
    unreadable or has none."""
    try:
        stored = pq.read_metadata(path).metadata or {}
        value = json.loads(stored[METADATA_KEY])
    except (OSError, KeyError, ValueError, pa.ArrowException):
        return None
    return value if isinstance(value, dict) else None


def write_atomically(path: Path, write: Callable[[BinaryIO], object]) -> None:
    """`write(handle)` into a temporary file beside `path`, synced, then renamed to `path`."""
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = temporary_path(path)
    try:
        with temporary.open("wb") as handle:
            write(handle)
            handle.flush()
            os.fsync(handle.fileno())
        temporary.replace(path)
    finally:
        temporary.unlink(missing_ok=True)
    fsync_folder(path.parent)


def write_table_atomically(path: Path, table: Any) -> None:
    """A whole Parquet table written to `path` atomically."""
    write_atomically(path, lambda handle: pq.write_table(table, handle, compression="zstd"))


def write_text_atomically(path: Path, text: str) -> None:
    """A UTF-8 text file written to `path` atomically."""
    write_atomically(path, lambda handle: handle.write(text.encode("utf-8")))
