"""Where the recorder's channels go: one MCAP file, or rotating MCAP segments in a folder.

A target is opened on the recorder's Foxglove context (its channels are then written to it),
told the recording's metadata once the first frame has come, ticked every `record.flush_s` by
the writer thread (the open chunk written out and synced to disk: the most a `kill -9` or a
power loss can lose; a segment due is rotated), and closed. The SDK writes through a
`TrackedFile`, which keeps the operating system's error of a failed write (the SDK itself says
only 'I/O error', at the next flush); `SinkErrors` keeps the SDK's warning per message logged
after a failed write off the log (the recorder reports the failure once).
"""

from __future__ import annotations

import logging
import os
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Protocol

import foxglove
from foxglove.mcap import MCAPCompression, MCAPWriteOptions, MCAPWriter

from roadgaze.config import RecordConfig
from roadgaze.errors import RoadgazeError
from roadgaze.outputs.foxglove.channels import TOPIC_IMAGE
from roadgaze.outputs.foxglove.segment_lock import PrefixLock, claim_prefix, segments_of

log = logging.getLogger(__name__)

MB = 1_000_000
OPEN_SUFFIX = ".part"
"""The open segment is `NAME.mcap.part`; closed (complete, indexed) it becomes `NAME.mcap`."""
_COMPRESSION = {"zstd": MCAPCompression.Zstd, "lz4": MCAPCompression.Lz4, "none": None}


class Target(Protocol):
    """One place the channels are written to (an MCAP file, the segments, the live server)."""

    def open(self, context: foxglove.Context) -> None: ...

    def images_wanted(self) -> bool:
        """Whether a camera frame taken now would reach this target."""
        ...

    def describe(self, metadata: Mapping[str, Mapping[str, str]]) -> None:
        """The recording's metadata records (name -> key -> value), once the first frame came."""
        ...

    def tick(self, now_s: float) -> None:
        """Every `flush_s` on the writer thread (monotonic `now_s`); raises on a failed write."""
        ...

    def close(self) -> None: ...


class SinkErrors(logging.Filter):
    """Keeps the SDK's 'error logging message' warnings (one per message after a failed write)
    off the log."""

    def filter(self, record: logging.LogRecord) -> bool:
        return not record.getMessage().startswith("error logging message")


SINK_ERRORS = SinkErrors()
for _name in ("foxglove", "foxglove.log_sink_set"):
    logging.getLogger(_name).addFilter(SINK_ERRORS)


class TrackedFile:
    """The file an MCAP writer writes: a binary file that keeps the first OS error of a write
    or flush (`error`), syncs to disk on request and knows its size."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.error: OSError | None = None
        self._file = path.open("wb")

    def write(self, data: bytes | bytearray) -> int:
        try:
            return self._file.write(data)
        except OSError as exc:
            self.error = self.error or exc
            raise

    def seek(self, offset: int, whence: int = os.SEEK_SET) -> int:
        try:
            return self._file.seek(offset, whence)  # a buffered file writes out its buffer
        except OSError as exc:
            self.error = self.error or exc
            raise

    def flush(self) -> None:
        try:
            self._file.flush()
        except OSError as exc:
            self.error = self.error or exc
            raise

    def sync(self) -> None:
        """What was written, on the disk (a power loss keeps it)."""
        self.flush()
        os.fsync(self._file.fileno())

    @property
    def size(self) -> int:
        return self._file.tell()

    def close(self) -> None:
        self._file.close()


def write_options(config: RecordConfig) -> MCAPWriteOptions:
    """Chunked, indexed MCAP; compression on the writer's own thread (none started for it)."""
    return MCAPWriteOptions(
        compression=_COMPRESSION[config.compression],
        chunk_size=config.chunk_kb * 1024,
        compression_threads=0,
    )


def write_failed(path: Path, exc: BaseException, file: TrackedFile | None) -> RoadgazeError:
    """The one-line error of a failed write to `path`: the operating system's reason."""
    cause: BaseException = exc if file is None or file.error is None else file.error
    text = cause.strerror if isinstance(cause, OSError) and cause.strerror else str(cause)
    return RoadgazeError(f"cannot write MCAP {path}: {text}")


class McapWriting:
    """One MCAP file being written: the SDK's writer on a `TrackedFile`."""

    def __init__(
        self, path: Path, context: foxglove.Context, config: RecordConfig, images: bool
    ) -> None:
        """Creates `path` (replaced if it exists) for every channel of `context` (without the
        camera frames unless `images`); `RoadgazeError` when it cannot."""
        self.path = path
        self.file: TrackedFile | None = None
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            self.file = TrackedFile(path)
            self.writer: MCAPWriter = foxglove.open_mcap(
                self.file,
                context=context,
                channel_filter=None if images else (lambda channel: channel.topic != TOPIC_IMAGE),
                writer_options=write_options(config),
            )
        except (OSError, RuntimeError) as exc:
            if self.file is not None:
                self.file.close()
            raise write_failed(path, exc, self.file) from None

    def write_metadata(self, metadata: Mapping[str, Mapping[str, str]]) -> None:
        try:
            for name, values in metadata.items():
                self.writer.write_metadata(name, dict(values))
        except (OSError, RuntimeError) as exc:
            raise write_failed(self.path, exc, self.file) from None

    def flush(self) -> int:
        """The open chunk written and synced to the disk; returns the file's size."""
        assert self.file is not None
        try:
            self.writer.flush()
            self.file.sync()
        except (OSError, RuntimeError) as exc:
            raise write_failed(self.path, exc, self.file) from None
        return self.file.size

    def close(self) -> None:
        """The summary and index written, the file synced and closed."""
        assert self.file is not None
        try:
            self.writer.close()
            self.file.sync()
        except (OSError, RuntimeError) as exc:
            raise write_failed(self.path, exc, self.file) from None
        finally:
            self.file.close()


class McapFile:
    """One MCAP file (`replay --mcap FILE`): the frames, indexed and complete once closed."""

    def __init__(self, path: Path, config: RecordConfig, images: bool) -> None:
        self.path = path
        self.config = config
        self.images = images
        self._writing: McapWriting | None = None

    def open(self, context: foxglove.Context) -> None:
        self._writing = McapWriting(self.path, context, self.config, self.images)

    def images_wanted(self) -> bool:
        return self.images

    def describe(self, metadata: Mapping[str, Mapping[str, str]]) -> None:
        assert self._writing is not None, "target not open"
        self._writing.write_metadata(metadata)

    def tick(self, now_s: float) -> None:
        if self._writing is not None:
            self._writing.flush()

    def close(self) -> None:
        writing, self._writing = self._writing, None
        if writing is not None:
            writing.close()


def segment_name(prefix: str, start_s: float, number: int) -> str:
    """`PREFIX-YYYYMMDDTHHMMSSZ-NNNN.mcap`: sorts by start time, then by number."""
    start = time.strftime("%Y%m%dT%H%M%SZ", time.gmtime(start_s))
    return f"{prefix}-{start}-{number:04d}.mcap"


def sync_folder(folder: Path) -> None:
    """Make a rename in `folder` survive a power loss."""
    try:
        handle = os.open(folder, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
    except OSError:
        return
    try:
        os.fsync(handle)
    except OSError:
        pass
    finally:
        os.close(handle)


class McapSegments:
    """`run --record DIR`: segments rotated by size and age, the folder kept under a bound.

    The open segment is `NAME.mcap.part`, flushed and synced every `flush_s`; closed, it is
    renamed `NAME.mcap` (complete and indexed). Before a segment opens, the oldest closed
    segments of this prefix are removed (each logged) until the closed ones and a full new one
    fit in `max_disk_mb`. A segment is rotated when its age reaches `segment_s` or when the next
    flush interval at the recent rate would take it over `segment_mb`. Parts left by a killed
    run are recovered when the folder is opened (`roadgaze.outputs.foxglove.recover`). The
    prefix is locked for the run (`segment_lock`): a second run with the same prefix records as
    `PREFIX.2` and never touches this one's segments; `prefix` is the one in use once open.
    """

    def __init__(
        self,
        folder: Path,
        config: RecordConfig,
        images: bool,
        prefix: str,
        wall_clock: Callable[[], float] = time.time,
    ) -> None:
        self.folder = folder
        self.config = config
        self.images = images
        self.prefix = prefix
        self._wall_clock = wall_clock
        self._context: foxglove.Context | None = None
        self._writing: McapWriting | None = None
        self._metadata: dict[str, dict[str, str]] = {}
        self._opened_s = 0.0
        self._last_size = 0
        self._last_tick_s = 0.0
        self.number = 0
        self.closed: list[Path] = []
        """The segments closed by this run, in order."""
        self.removed: list[Path] = []
        """The segments removed to keep the folder under `max_disk_mb`."""
        self._lock: PrefixLock | None = None

    def open(self, context: foxglove.Context) -> None:
        from roadgaze.outputs.foxglove.recover import recover_parts

        try:
            self.folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise RoadgazeError(
                f"cannot record into {self.folder}: {exc.strerror or exc}"
            ) from None
        self._lock, self.prefix = claim_prefix(self.folder, self.prefix)
        try:
            for part in segments_of(self.folder, self.prefix, OPEN_SUFFIX):
                recover_parts(self.folder, part.name)  # a literal name: only this one
            self._context = context
            self._open_next(time.monotonic())
        except BaseException:
            self._release()
            raise

    def images_wanted(self) -> bool:
        return self.images

    def segments_on_disk(self) -> list[Path]:
        """This prefix's closed segments in the folder, oldest first."""
        found = segments_of(self.folder, self.prefix)
        return sorted(found, key=lambda path: (path.stat().st_mtime_ns, path.name))

    def _make_room(self) -> None:
        bound = self.config.max_disk_mb * MB
        segments = self.segments_on_disk()
        used = sum(path.stat().st_size for path in segments)
        while segments and used + self.config.segment_mb * MB > bound:
            oldest = segments.pop(0)
            size = oldest.stat().st_size
            oldest.unlink()
            used -= size
            self.removed.append(oldest)
            log.warning(
                "record: removed the oldest segment %s (%.1f MB) to keep %s under "
                "record.max_disk_mb = %g MB",
                oldest.name,
                size / MB,
                self.folder,
                self.config.max_disk_mb,
            )

    def _segment_metadata(self) -> dict[str, dict[str, str]]:
        return {
            name: {**values, "segment": str(self.number)} if name == "roadgaze" else values
            for name, values in self._metadata.items()
        }

    def _open_next(self, now_s: float) -> None:
        assert self._context is not None
        self._make_room()
        self.number += 1
        name = segment_name(self.prefix, self._wall_clock(), self.number)
        part = self.folder / f"{name}{OPEN_SUFFIX}"
        self._writing = McapWriting(part, self._context, self.config, self.images)
        self._opened_s = self._last_tick_s = now_s
        self._last_size = 0
        if self._metadata:
            self._writing.write_metadata(self._segment_metadata())
        log.info("record: segment %s open", part.name)

    def describe(self, metadata: Mapping[str, Mapping[str, str]]) -> None:
        self._metadata = {name: dict(values) for name, values in metadata.items()}
        assert self._writing is not None, "target not open"
        self._writing.write_metadata(self._segment_metadata())

    def tick(self, now_s: float) -> None:
        if self._writing is None:
            return
        size = self._writing.flush()
        rate_bytes_per_s = max(0.0, (size - self._last_size) / max(now_s - self._last_tick_s, 1e-3))
        self._last_size, self._last_tick_s = size, now_s
        full = size + rate_bytes_per_s * self.config.flush_s >= self.config.segment_mb * MB
        if full or now_s - self._opened_s >= self.config.segment_s:
            self._close_current()
            self._open_next(now_s)

    def _close_current(self) -> None:
        writing, self._writing = self._writing, None
        if writing is None:
            return
        part = writing.path
        closed = part.with_name(part.name.removesuffix(OPEN_SUFFIX))
        writing.close()
        try:
            part.replace(closed)
        except OSError as exc:
            raise write_failed(part, exc, None) from None
        sync_folder(self.folder)
        self.closed.append(closed)
        log.info("record: segment %s closed (%.1f MB)", closed.name, closed.stat().st_size / MB)

    def close(self) -> None:
        try:
            self._close_current()
        finally:
            self._release()

    def _release(self) -> None:
        lock, self._lock = self._lock, None
        if lock is not None:
            lock.release()
