"""MCAP records read in order in memory bounded by a setting, not by what the file claims.

The `mcap` reader decompresses each chunk whole into memory, sized by the chunk's own claim: a
28 kB file whose zstd chunk declares 768 MiB took 1.7 GB. Here chunks come from the reader
still compressed (`emit_chunks`), a chunk that declares more than `max_chunk_bytes` (the
`record.max_chunk_mib` setting) is refused before a byte of it is decompressed, and the rest are
decompressed into no more than their declared size: a chunk holding more than it declares is
damaged, however its compressed frames describe themselves. Records outside chunks (and the
compressed chunks themselves) are limited to about the same size by the reader's record limit.
Needs the `mcap` package (`roadgaze[foxglove]`).
"""

from __future__ import annotations

import os
import struct
from collections.abc import Iterator
from dataclasses import replace
from typing import IO, Any

from roadgaze.config.record import RecordConfig
from roadgaze.errors import SourceError

DEFAULT_MAX_CHUNK_MIB: float = RecordConfig.model_fields["max_chunk_mib"].default
"""The default of `record.max_chunk_mib`."""


class ChunkTooLargeError(SourceError):
    """An MCAP chunk (or record) larger than `record.max_chunk_mib`: refused, never read."""


def max_chunk_bytes(max_chunk_mib: float) -> int:
    """`record.max_chunk_mib` in bytes."""
    return int(max_chunk_mib * (1 << 20))


def _too_large(name: str, what: str, limit: int) -> ChunkTooLargeError:
    return ChunkTooLargeError(
        f"MCAP recording {name}: {what}, above record.max_chunk_mib ({limit / (1 << 20):g} MiB), "
        "the memory a chunk may take; not read. If the recording is genuine, raise the limit, "
        "e.g. --set record.max_chunk_mib=256"
    )


class CountingReader:
    """A binary stream that counts what was read from it (where the last record ended)."""

    def __init__(self, stream: IO[bytes] | Any) -> None:
        self._stream = stream
        self.position = 0
        self.last = b""
        """The bytes of the last read (a record's length field, when the reader refuses it)."""

    def read(self, size: int = -1) -> bytes:
        data: bytes = self._stream.read(size)
        self.position += len(data)
        self.last = data
        return data


def top_level_records(
    stream: IO[bytes], limit_bytes: int, name: str, validate_crc: bool = False
) -> Iterator[tuple[Any, list[Any], int]]:
    """(record, the records in it, the offset where it ends) for each top-level record of an
    MCAP file read from its start, in file order: a chunk's schemas, channels and messages,
    decompressed within `limit_bytes` (its CRC checked with `validate_crc`); any other record
    with itself alone. Raises `ChunkTooLargeError` for a chunk or record above the limit that
    the file holds; a damaged or cut record (one that claims more than the file has left)
    raises what the `mcap` reader raises (a cut file)."""
    from mcap.exceptions import EndOfFile, RecordLengthLimitExceeded
    from mcap.records import Chunk
    from mcap.stream_reader import StreamReader

    counted = CountingReader(stream)
    # A compressed chunk may come out a little larger than its content (zstd's worst case is
    # 1/256 more): the record limit leaves room for that and for the chunk's header.
    record_limit = limit_bytes + limit_bytes // 128 + 65536
    reader = StreamReader(
        counted,  # type: ignore[arg-type]
        skip_magic=False,
        emit_chunks=True,
        record_size_limit=record_limit,
    )
    records = reader.records
    while True:
        try:
            record = next(records, None)
        except RecordLengthLimitExceeded as exc:
            claimed = struct.unpack("<Q", counted.last)[0] if len(counted.last) == 8 else 0
            if claimed > _left_bytes(stream, counted.position):  # kill -9 mid-record
                raise EndOfFile(f"cut inside a record that claims {claimed} bytes") from None
            raise _too_large(name, f"a record too long ({exc})", limit_bytes) from None
        if record is None:
            return
        if isinstance(record, Chunk):
            inner = chunk_records(record, limit_bytes, name, validate_crc)
            yield record, inner, counted.position
        else:
            yield record, [record], counted.position


def _left_bytes(stream: Any, position: int) -> int:
    """What the file holds after `position` (unbounded when it is not a file)."""
    try:
        return int(os.fstat(stream.fileno()).st_size) - position
    except (AttributeError, OSError, ValueError):
        return 1 << 62


def chunk_records(chunk: Any, limit_bytes: int, name: str, validate_crc: bool = False) -> list[Any]:
    """The schemas, channels and messages of one chunk, decompressed within `limit_bytes`
    (`ChunkTooLargeError` above it, checked against the declared size before decompressing)."""
    from mcap.stream_reader import breakup_chunk

    declared = int(chunk.uncompressed_size)
    if declared > limit_bytes:
        raise _too_large(
            name, f"a chunk declares {declared / (1 << 20):.1f} MiB uncompressed", limit_bytes
        )
    data = _decompressed(chunk.compression, chunk.data, declared)
    return list(breakup_chunk(replace(chunk, compression="", data=data), validate_crc))


def _decompressed(compression: str, data: bytes, declared: int) -> bytes:
    """The `declared` bytes of a chunk's content; ValueError (a damaged chunk) when it holds
    more or fewer. Never more than `declared` bytes are allocated for it: a zstd frame that
    announces a larger content is refused unread (zstd would allocate what it announces)."""
    if compression == "":
        content = data
    elif compression == "zstd":
        import zstandard

        announced = zstandard.frame_content_size(data)
        if announced > declared:
            raise ValueError(f"a chunk that declares {declared} bytes holds {announced}")
        content = zstandard.ZstdDecompressor().decompress(data, max_output_size=declared)
    elif compression == "lz4":
        import lz4.frame  # type: ignore[import-untyped]

        decompressor = lz4.frame.LZ4FrameDecompressor()
        content = decompressor.decompress(data, max_length=declared)
        if not decompressor.eof:
            raise ValueError(f"a chunk that declares {declared} bytes holds more (or is cut)")
    else:
        raise ValueError(f"unknown chunk compression {compression!r}")
    if len(content) != declared:
        raise ValueError(f"a chunk that declares {declared} bytes holds {len(content)}")
    return content
