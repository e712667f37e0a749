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

    def __init__(self, path: str | Path, topic: str | None = None) -> None:
        self.path = Path(path)
        if not self.path.is_file():
            raise SourceError(f"MCAP recording {self.path} not found; pass an existing file")
        _require_mcap(self.path)
        self._requested_topic = topic
        self._status = SourceStatus()
        self._truncation: str | None = None
        self._drivers = RecordedDrivers()  # the driver recorded with each frame (mcap_driver)
        try:
            self._handle: IO[bytes] | None = self.path.open("rb")
        except OSError as exc:
            raise SourceError(f"cannot read MCAP recording {self.path}: {exc.strerror}") from None
        try:
            summary, metadata = self._summary_and_metadata()
            self.offset_ns: int | None = _offset_ns(metadata)
            self.topic, self._count = self._choose_topic(summary)
            self._frames = self._read_frames()
            first = next(self._frames, None)
        except BaseException:
            self.close()
            raise
        if first is None:
            self.close()
            raise SourceError(
                f"MCAP recording {self.path} holds no readable camera frame on "
                f"{self.topic or 'an image channel'}"
                + (f" (it is cut short: {self._truncation})" if self._truncation else "")
            )
        self._first: CameraImage | None = first[0]
        self._first_log_ns = first[1]
        height, width = first[0].image.shape[:2]
        self._info = SourceInfo(
            name=str(self.path),
            live=False,
            fps=_fps(summary, self._count),
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
        unreadable record (a recording cut short)."""
        from mcap.records import Channel, Footer, Message, Metadata, Schema
        from mcap.stream_reader import StreamReader

        assert self._handle is not None
        schemas: dict[int, Any] = {}
        decoders: dict[int, ImageDecoder] = {}
        driver_channels: set[int] = set()
        reader = StreamReader(self._handle, skip_magic=False)
        records = iter(reader.records)
        while True:
            try:
                record = next(records, None)
            except Exception as exc:  # cut short or damaged: what was read is kept
                self._cut(exc)
                return
            if record is None:
                # Ended between two records without the footer: the writer never closed it
                # (`kill -9` or a power loss after a whole chunk), so it is cut short too.
                self._truncation = self._truncation or "no footer after the last complete record"
                return
            if isinstance(record, Footer):
                return
            if isinstance(record, Schema):
                schemas[record.id] = record
            elif isinstance(record, Metadata) and self.offset_ns is None:
                self.offset_ns = _offset_ns([record])
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
        except SourceError:
            raise
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
        period_s = 1.0 / (self._info.fps or 30.0)
        first_ns = None
        previous_t_s: float | None = None
        index = 0
        item: tuple[CameraImage, int] | None = (
            (self._first, self._first_log_ns) if self._first else None
        )
        self._first = None
        while item is not None:
            camera, log_ns = item
            stamp_ns = camera.stamp_ns or log_ns
            if self.offset_ns is None:
                first_ns = stamp_ns if first_ns is None else first_ns
                t_s = (stamp_ns - first_ns) / 1e9
            else:
                t_s = (stamp_ns - self.offset_ns) / 1e9
            if previous_t_s is not None and t_s <= previous_t_s:
                t_s = previous_t_s + period_s
            self._status = replace(self._status, frames_delivered=index + 1)
            yield Frame(index, t_s, camera.image, self._drivers.take(log_ns))
            previous_t_s = t_s
            index += 1
            item = next(self._frames, None)
        self._finish(index, previous_t_s)

    def _finish(self, delivered: int, last_t_s: float | None) -> None:
        cut = self._truncation
        message = None
        if cut is not None:
            message = (
                f"MCAP recording {self.path} is cut short ({cut}): read {delivered} frames, "
                f"stopped after t={last_t_s or 0.0:.3f} s; `roadgaze recover` makes it whole"
            )
            log.warning(message)
        self._status = replace(
            self._status, ended=True, truncated=message is not None, message=message
        )

    def close(self) -> None:
        if self._handle is not None:
            self._handle.close()
            self._handle = None


def _offset_ns(metadata: list[Any]) -> int | None:
    """The `roadgaze` metadata's `time_offset_ns`; None when the recording has none."""
    for record in metadata:
        if record.name == "roadgaze" and "time_offset_ns" in record.metadata:
            try:
                return int(record.metadata["time_offset_ns"])
            except ValueError:
                return None
    return None


def _fps(summary: Any, count: int | None) -> float | None:
    """Frames per second from the summary's statistics (the recording's span)."""
    statistics = getattr(summary, "statistics", None)
    if statistics is None or not count or count < 2:
        return None
    span_ns = statistics.message_end_time - statistics.message_start_time
    return (count - 1) / (span_ns / 1e9) if span_ns > 0 else None
