"""A recording cut short (`kill -9`, a power loss, a full disk) made whole again.

An MCAP file is written as a header, then records (schemas, channels, metadata and chunks of
messages), and at the close a summary with the chunk index and a footer. Cut short, it lacks the
summary and footer, and its last chunk may be half written. `recover_mcap` reads the records in
order with the `mcap` reader until the first one that is incomplete or fails its CRC, and
writes what it read into a new, indexed file: every message of every complete chunk is kept;
lost are the chunk that was being written (at most `record.flush_s` of data: the writer writes
and syncs its open chunk that often) and anything after a damaged record.

A recovery never overwrites a file: the recovered recording takes its name only if that name is
free at the moment it is placed (a hard link, which fails on an existing name), else the next
free `NAME-1.mcap`, `NAME-2.mcap`, ... (or, asked for one exact name, it is refused).
"""

from __future__ import annotations

import contextlib
import logging
import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from mcap.records import Channel, Chunk, Header, Message, Metadata, Schema
from mcap.writer import CompressionType, Writer

from roadgaze.capture.mcap import MCAP_MAGIC
from roadgaze.capture.mcap_records import (
    DEFAULT_MAX_CHUNK_MIB,
    ChunkTooLargeError,
    max_chunk_bytes,
    top_level_records,
)
from roadgaze.errors import RoadgazeError
from roadgaze.outputs.foxglove.targets import OPEN_SUFFIX

log = logging.getLogger(__name__)


@dataclass(frozen=True, slots=True)
class Recovery:
    """What a recovery kept and what it could not."""

    source: Path
    path: Path
    messages: int
    chunks: int
    first_log_time_ns: int | None
    last_log_time_ns: int | None
    bytes_read: int
    """Bytes of the source up to the end of its last complete record."""
    bytes_lost: int
    """Bytes after that: the half-written chunk (or summary) that cannot be read."""
    stopped_because: str
    """Why reading stopped: `end of file`, or the error of the first unreadable record."""

    def describe(self) -> str:
        span = ""
        if self.first_log_time_ns is not None and self.last_log_time_ns is not None:
            span = f" ({(self.last_log_time_ns - self.first_log_time_ns) / 1e9:.1f} s)"
        kept = f"{self.messages} messages in {self.chunks} chunks{span} kept"
        if self.stopped_because == "end of file":
            return f"{kept}; the file was complete"
        if self.bytes_lost == 0:
            return f"{kept}; it ended after its last complete chunk (nothing half written)"
        return (
            f"{kept}; lost the {self.bytes_lost} bytes of the chunk being written "
            f"({self.stopped_because})"
        )


def recover_mcap(
    source: Path,
    path: Path,
    *,
    exact: bool = False,
    max_chunk_mib: float = DEFAULT_MAX_CHUNK_MIB,
) -> Recovery:
    """Write every readable message of `source` (an MCAP file, complete or cut short) into a
    new, indexed MCAP file: `path` when no file has that name, else the first free
    `free_names(path)` (`Recovery.path` says which); written beside it, then placed without ever
    replacing a file. Raises `RoadgazeError` when `source` is not an MCAP file or holds no
    readable record, with `exact` when `path` exists, and when a chunk declares more than
    `max_chunk_mib` (`record.max_chunk_mib`: never decompressed)."""
    if exact and (path.exists() or path.is_symlink()):
        raise RoadgazeError(
            f"{path} exists; recover never overwrites a file: remove it or choose another --out"
        )
    size = source.stat().st_size
    temporary = path.with_name(f".{path.name}.recovering")
    schemas: dict[int, int] = {}
    channels: dict[int, int] = {}
    messages = chunks = 0
    first_ns: int | None = None
    last_ns: int | None = None
    good_end = 0
    stopped = "end of file"
    try:
        with source.open("rb") as raw, temporary.open("wb") as out:
            writer = Writer(out, compression=CompressionType.ZSTD)
            started = False
            iterator = top_level_records(
                raw, max_chunk_bytes(max_chunk_mib), str(source), validate_crc=True
            )
            while True:
                try:
                    item = next(iterator, None)
                    if item is None:  # the footer and the closing magic read
                        good_end += len(MCAP_MAGIC)
                        break
                    record, inner, end = item
                except ChunkTooLargeError:
                    raise
                except Exception as exc:  # the first unreadable record ends the recovery
                    stopped = f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__
                    break
                if isinstance(record, Header):
                    writer.start(profile=record.profile, library=record.library)
                    started = True
                    good_end = end
                    continue
                if not started:
                    raise RoadgazeError(f"{source} is not an MCAP recording (no header)")
                for entry in inner:
                    if isinstance(entry, Schema) and entry.id not in schemas:
                        schemas[entry.id] = writer.register_schema(
                            entry.name, entry.encoding, entry.data
                        )
                    elif isinstance(entry, Channel) and entry.id not in channels:
                        channels[entry.id] = writer.register_channel(
                            entry.topic,
                            entry.message_encoding,
                            schemas.get(entry.schema_id, 0),
                            dict(entry.metadata),
                        )
                    elif isinstance(entry, Message) and entry.channel_id in channels:
                        writer.add_message(
                            channels[entry.channel_id],
                            entry.log_time,
                            entry.data,
                            entry.publish_time,
                            entry.sequence,
                        )
                        messages += 1
                        first_ns = (
                            entry.log_time if first_ns is None else min(first_ns, entry.log_time)
                        )
                        last_ns = (
                            entry.log_time if last_ns is None else max(last_ns, entry.log_time)
                        )
                    elif isinstance(entry, Metadata):
                        writer.add_metadata(entry.name, dict(entry.metadata))
                chunks += isinstance(record, Chunk)
                good_end = end
            if not started:
                raise RoadgazeError(f"{source} is not an MCAP recording ({stopped})")
            writer.finish()  # type: ignore[no-untyped-call]
            out.flush()
            os.fsync(out.fileno())
        path = _place(temporary, path, exact)
    except OSError as exc:
        with contextlib.suppress(OSError):
            temporary.unlink()
        raise RoadgazeError(f"cannot recover {source}: {exc.strerror or exc}") from None
    except BaseException:
        with contextlib.suppress(OSError):
            temporary.unlink()
        raise
    return Recovery(
        source=source,
        path=path,
        messages=messages,
        chunks=chunks,
        first_log_time_ns=first_ns,
        last_log_time_ns=last_ns,
        bytes_read=good_end,
        bytes_lost=max(0, size - good_end),
        stopped_because=stopped,
    )


def free_names(path: Path) -> Iterator[Path]:
    """`path`, then `NAME-1.SUFFIX`, `NAME-2.SUFFIX`, ... up to `NAME-999.SUFFIX`."""
    yield path
    for number in range(1, 1000):
        yield path.with_name(f"{path.stem}-{number}{path.suffix}")


def _place(temporary: Path, path: Path, exact: bool) -> Path:
    """Give `temporary` the first free name of `free_names(path)` (only `path` when `exact`)
    without replacing any file; returns the name taken."""
    for candidate in [path] if exact else free_names(path):
        try:
            os.link(temporary, candidate)  # fails, never replaces, when the name is taken
        except FileExistsError:
            continue
        except OSError:  # a file system without hard links: checked, then renamed
            if candidate.exists() or candidate.is_symlink():
                continue
            temporary.replace(candidate)
            return candidate
        temporary.unlink()
        return candidate
    raise RoadgazeError(
        f"{path} exists (and {'no other name was asked for' if exact else 'so do 999 others'}); "
        "recover never overwrites a file: remove it or choose another --out"
    )


def recovered_name(part: Path) -> Path:
    """`NAME.mcap.part` -> `NAME.mcap`; any other name gets `.recovered.mcap`."""
    if part.name.endswith(f".mcap{OPEN_SUFFIX}"):
        return part.with_name(part.name.removesuffix(OPEN_SUFFIX))
    return part.with_name(f"{part.stem}.recovered.mcap")


def recover_parts(folder: Path, pattern: str) -> list[Recovery]:
    """Recover every open segment (`pattern`) a killed run left in `folder`, each logged; a part
    that cannot be recovered is renamed `.unreadable` and left (logged)."""
    done: list[Recovery] = []
    for part in sorted(folder.glob(pattern)):
        try:
            recovery = recover_mcap(part, recovered_name(part))
        except RoadgazeError as exc:
            part.replace(part.with_name(f"{part.name}.unreadable"))
            log.warning("record: cannot recover %s, left as .unreadable: %s", part.name, exc)
            continue
        part.unlink()
        done.append(recovery)
        log.warning(
            "record: recovered %s left open by an interrupted run into %s: %s",
            part.name,
            recovery.path.name,
            recovery.describe(),
        )
    return done
