"""An MCAP recording as a drive: the frames of its camera channel, timed by their own stamps.

The camera channel is `record.camera_topic` when set, else the recording's only image channel
(`foxglove.CompressedImage` JPEG/PNG or `foxglove.RawImage`), else `/camera/image`. Each frame's
time is its message's header stamp (the log time when the header has none) less the recording's
`roadgaze` time offset (`time_offset_ns` metadata: 0 for a replay's recording, the wall-clock
offset of a `run --record` segment), so a recording replays on the timeline of the source it was
recorded from; a recording roadgaze did not write starts at its first frame. Times are made
strictly increasing as for a video file. A recording cut short (no summary: `kill -9`, a power
loss) is read up to its last complete chunk and reported truncated; a frame whose picture does
not decode is skipped, logged and counted. Needs the `mcap` package (`roadgaze[foxglove]`).
"""

from __future__ import annotations

import logging
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path
from typing import IO, Any

from roadgaze.capture.base import SourceBase, SourceInfo, SourceStatus
from roadgaze.capture.mcap_driver import DRIVER_TOPIC, RecordedDrivers
from roadgaze.capture.mcap_images import IMAGE_SCHEMAS, CameraImage, ImageDecoder
from roadgaze.capture.mcap_records import (
    DEFAULT_MAX_CHUNK_MIB,
    ChunkTooLargeError,
    max_chunk_bytes,
    top_level_records,
)
from roadgaze.capture.timebase import JoinedTimeBase, sane_fps
from roadgaze.errors import SourceError
from roadgaze.types import Frame

log = logging.getLogger(__name__)

MCAP_MAGIC = b"\x89MCAP0\r\n"
DEFAULT_CAMERA_TOPIC = "/camera/image"
FOXGLOVE_EXTRA = "pip install 'roadgaze[foxglove]'"


def is_mcap(path: Path) -> bool:
    """Whether the file starts with MCAP's magic bytes."""
    try:
        with path.open("rb") as handle:
            return handle.read(len(MCAP_MAGIC)) == MCAP_MAGIC
    except OSError:
        return False


def _require_mcap(path: Path) -> None:
    try:
        import mcap  # noqa: F401  (only asked whether it is there)
    except ImportError:
        raise SourceError(
            f"{path} is an MCAP recording; reading it needs the MCAP reader, which is not "
            f"installed: {FOXGLOVE_EXTRA}"
        ) from None


class McapSource(SourceBase):
    """Every frame of an MCAP recording's camera channel (see the module doc)."""

    def __init__(
        self,
        path: str | Path,
        topic: str | None = None,
        max_chunk_mib: float = DEFAULT_MAX_CHUNK_MIB,
    ) -> None:
        self.path = Path(path)
        self._max_chunk_bytes = max_chunk_bytes(max_chunk_mib)
        if not self.path.is_file():
            raise SourceError(f"MCAP recording {self.path} not found; pass an existing file")
        _require_mcap(self.path)
        self._requested_topic = topic
        self._status = SourceStatus()
        self._truncation: str | None = None
        self._drivers = RecordedDrivers()  # the driver recorded with each frame (mcap_driver)
        self._first_skip: str | None = None
        """Why the first skipped camera frame was skipped."""
        self._offset_seen = False
        """Whether the recording's time offset was read (good or bad)."""
        try:
            self._handle: IO[bytes] | None = self.path.open("rb")
        except OSError as exc:
            raise SourceError(f"cannot read MCAP recording {self.path}: {exc.strerror}") from None
        try:
            summary, metadata = self._summary_and_metadata()
            self.offset_ns: int | None = self._checked_offset(metadata)
            self.topic, self._count = self._choose_topic(summary)
            self._frames = self._read_frames()
            first = next(self._frames, None)
        except BaseException:
            self.close()
            raise
        if first is None:
            self.close()
            skipped = self._status.frames_skipped
            raise SourceError(
                f"MCAP recording {self.path} holds no readable camera frame on "
                f"{self.topic or 'an image channel'}"
                + (f" (it is cut short: {self._truncation})" if self._truncation else "")
                + (f" ({skipped} skipped: {self._first_skip})" if skipped else "")
            )
        self._first: CameraImage | None = first[0]
        self._first_log_ns = first[1]
        height, width = first[0].image.shape[:2]
        self._info = SourceInfo(
            name=str(self.path),
            live=False,
            fps=sane_fps(_fps(summary, self._count)),
            frame_count=self._count,
            width=int(width),
            height=int(height),
        )
        self._iterated = False

    @property
    def info(self) -> SourceInfo:
        return self._info

    def _summary_and_metadata(self) -> tuple[Any, list[Any]]:
        from mcap.reader import make_reader

        assert self._handle is not None
        try:
            reader = make_reader(self._handle)
            summary = reader.get_summary()
            metadata = list(reader.iter_metadata()) if summary is not None else []
        except Exception:  # cut short: no footer, or a damaged summary; read it in order
            summary, metadata = None, []
        self._handle.seek(0)
        return summary, metadata

    def _choose_topic(self, summary: Any) -> tuple[str | None, int | None]:
        """The camera topic and its frame count (None when unknown: no summary)."""
        if summary is None:
            return self._requested_topic, None
        images = {
            channel.topic: channel.id
            for channel in summary.channels.values()
            if channel.schema_id in summary.schemas
            and summary.schemas[channel.schema_id].name in IMAGE_SCHEMAS
        }
        wanted = self._requested_topic
        if wanted is None and len(images) == 1:
            wanted = next(iter(images))
        wanted = wanted or DEFAULT_CAMERA_TOPIC
        if wanted not in images:
            found = ", ".join(sorted(images)) or "none"
            raise SourceError(
                f"MCAP recording {self.path} has no camera channel {wanted} (image channels: "
                f"{found}); name one with --set record.camera_topic=TOPIC"
            )
        counts = summary.statistics.channel_message_counts if summary.statistics else {}
        return wanted, counts.get(images[wanted])

    def _read_frames(self) -> Iterator[tuple[CameraImage, int]]:
        """(frame, log time) of each camera message in file order, until the end or the first
        unreadable record (a recording cut short). A chunk above `record.max_chunk_mib` raises
        `ChunkTooLargeError` (roadgaze.capture.mcap_records)."""
        from mcap.records import Channel, Footer, Message, Metadata, Schema

        assert self._handle is not None
        schemas: dict[int, Any] = {}
        decoders: dict[int, ImageDecoder] = {}
        driver_channels: set[int] = set()
        records = top_level_records(self._handle, self._max_chunk_bytes, str(self.path))
        while True:
            try:
                item = next(records, None)
            except ChunkTooLargeError:
                raise
            except Exception as exc:  # cut short or damaged: what was read is kept
                self._cut(exc)
                return
            if item is None:
                # Ended between two records without the footer: the writer never closed it
                # (`kill -9` or a power loss after a whole chunk), so it is cut short too.
                self._truncation = self._truncation or "no footer after the last complete record"
                return
            for record in item[1]:
                if isinstance(record, Footer):
                    return
                if isinstance(record, Schema):
                    schemas[record.id] = record
                elif isinstance(record, Metadata) and not self._offset_seen:
                    self.offset_ns = self._checked_offset([record])
                elif isinstance(record, Channel):
                    if record.topic == DRIVER_TOPIC:
                        driver_channels.add(record.id)
                    decoder = self._decoder_of(record, schemas.get(record.schema_id))
                    if decoder is not None:
                        decoders[record.id] = decoder
                elif isinstance(record, Message) and record.channel_id in driver_channels:
                    self._drivers.note(record.log_time, record.data)
                elif isinstance(record, Message) and record.channel_id in decoders:
                    decoded = self._decode(decoders[record.channel_id], record)
                    if decoded is not None:
                        yield decoded

    def _checked_offset(self, metadata: list[Any]) -> int | None:
        """The recording's time offset; a malformed one is said in a warning and ignored (the
        frames' own stamps still time the drive, from its first frame)."""
        value, problem = _offset_ns(metadata)
        self._offset_seen = self._offset_seen or value is not None or problem is not None
        if problem is not None:
            log.warning(
                "MCAP recording %s: its roadgaze time_offset_ns %s: ignored; the drive is "
                "timed from its first frame",
                self.path,
                problem,
            )
        return value

    def _decoder_of(self, channel: Any, schema: Any) -> ImageDecoder | None:
        if schema is None or schema.name not in IMAGE_SCHEMAS:
            return None
        if self.topic is None:
            self.topic = channel.topic  # cut short: the first image channel
        if channel.topic != self.topic:
            return None
        return ImageDecoder(schema.name, schema.encoding, schema.data, channel.message_encoding)

    def _decode(self, decoder: ImageDecoder, message: Any) -> tuple[CameraImage, int] | None:
        try:
            frame = decoder.decode(message.data)
        except SourceError as exc:  # e.g. a RawImage whose bytes do not fill its size
            frame, reason = None, str(exc)
        except Exception as exc:  # a damaged message: skipped like an unreadable image
            frame, reason = None, f"{type(exc).__name__}: {exc}"
        else:
            reason = "the picture does not decode"
        if frame is None:
            log.warning(
                "skipping camera frame at log time %d ns of %s: %s",
                message.log_time,
                self.path,
                reason,
            )
            self._first_skip = self._first_skip or reason
            self._status = replace(self._status, frames_skipped=self._status.frames_skipped + 1)
            return None
        return frame, message.log_time

    def _cut(self, exc: Exception) -> None:
        self._truncation = f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__

    def __iter__(self) -> Iterator[Frame]:
        if self._iterated:
            raise SourceError(
                f"MCAP recording {self.path} can be iterated only once; open it again"
            )
        self._iterated = True
        time_base = JoinedTimeBase(f"MCAP recording {self.path}", self._info.fps)
        origin_ns: int | None = None
        previous_t_s: float | None = None
        index = 0
        item: tuple[CameraImage, int] | None = (
            (self._first, self._first_log_ns) if self._first else None
        )
        self._first = None
        while item is not None:
            camera, log_ns = item
            stamp_ns = camera.stamp_ns or log_ns
            if origin_ns is None:  # the timeline is chosen once, at the first frame
                origin_ns = self._origin_ns(stamp_ns)
            t_s = time_base.t_s(index, (stamp_ns - origin_ns) / 1e9)
            if time_base.breaks and self._status.message is None:
                message = (
                    f"MCAP recording {self.path}: {time_base.first_break}: the clock is joined "
                    "across it"
                )
                self._status = replace(self._status, message=message)
            self._status = replace(self._status, frames_delivered=index + 1)
            yield Frame(index, t_s, camera.image, self._drivers.take(log_ns))
            previous_t_s = t_s
            index += 1
            item = next(self._frames, None)
        self._finish(index, previous_t_s, time_base)

    def _origin_ns(self, first_stamp_ns: int) -> int:
        """Where the drive's time 0 lies: the recording's time offset, or its first frame when
        it has none or the offset lies after the first frame (it is then not this recording's;
        said in a warning)."""
        if self.offset_ns is not None and first_stamp_ns < self.offset_ns:
            log.warning(
                "MCAP recording %s: its time_offset_ns (%d) lies after its first frame's stamp "
                "(%d ns): ignored; the drive is timed from its first frame",
                self.path,
                self.offset_ns,
                first_stamp_ns,
            )
            self.offset_ns = None
        return first_stamp_ns if self.offset_ns is None else self.offset_ns

    def _finish(self, delivered: int, last_t_s: float | None, time_base: JoinedTimeBase) -> None:
        """The status at the end: cut short, clock breaks and skipped frames, in one message
        (a replay's closing lines and a batch's warnings show it)."""
        problems = []
        if self._truncation is not None:
            problems.append(
                f"cut short ({self._truncation}): read {delivered} frames, stopped after "
                f"t={last_t_s or 0.0:.3f} s; `roadgaze recover` makes it whole"
            )
            log.warning("MCAP recording %s is %s", self.path, problems[-1])
        if time_base.breaks:
            problems.append(
                f"its clock was joined across {time_base.breaks} "
                f"break{'s' if time_base.breaks > 1 else ''} (the first: {time_base.first_break})"
            )
        skipped = self._status.frames_skipped
        if skipped:
            problems.append(
                f"{skipped} camera frame{'s' if skipped > 1 else ''} skipped (the first: "
                f"{self._first_skip})"
            )
        self._status = replace(
            self._status,
            ended=True,
            truncated=self._truncation is not None,
            message=f"MCAP recording {self.path}: {'; '.join(problems)}" if problems else None,
        )

    def close(self) -> None:
        if self._handle is not None:
            self._handle.close()
            self._handle = None


def _offset_ns(metadata: list[Any]) -> tuple[int | None, str | None]:
    """The `roadgaze` metadata's `time_offset_ns` (None when the recording has none), and what
    is wrong with it when it is not a time (an integer of 0 to 2^64 - 1 ns, as MCAP's times)."""
    for record in metadata:
        if record.name == "roadgaze" and "time_offset_ns" in record.metadata:
            text = str(record.metadata["time_offset_ns"])
            try:
                value = int(text)
            except ValueError:
                return None, f"{text[:40]!r} is not an integer"
            if not 0 <= value < 1 << 64:
                return None, f"{text[:40]} ns lies outside MCAP's times (0 to 2^64 - 1 ns)"
            return value, None
    return None, None


def _fps(summary: Any, count: int | None) -> float | None:
    """Frames per second from the summary's statistics (the recording's span)."""
    statistics = getattr(summary, "statistics", None)
    if statistics is None or not count or count < 2:
        return None
    span_ns = statistics.message_end_time - statistics.message_start_time
    return (count - 1) / (span_ns / 1e9) if span_ns > 0 else None
