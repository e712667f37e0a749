"""The pipeline sink that records every frame to MCAP and serves it live, off the loop's thread.

On the loop's thread `on_record` only stamps the record with its capture time and queues it (and,
at `record.image_fps`, the frame's image): about 10 us. A writer thread takes what was queued
every `WRITE_BATCH_S`, turns each record into its messages (`FrameChannels`) and logs them to
the targets (an MCAP file, the rotating segments, the live server), ticks them every
`record.flush_s` and records the state every `record.state_interval_s`; an image thread (at
lower priority) scales and encodes the camera frames. The record queue is bounded and never
drops: the loop waits when it is full (logged). A camera frame is dropped (and counted) when two
wait already, unless `block_on_images` (a replay read flat out waits instead, so its recording
has every frame it asked for). roadgaze's log lines (INFO and up) are recorded too, stamped with
the capture time of the last frame queued.

Capture time: on the source's timeline (`t_s`) for a replay, so the recording's clock is the
video's; on the wall clock for `run` (`t_s` plus the offset between the two at the first frame),
so segments of one drive and of the next line up. The offset is in each file's `roadgaze`
metadata, and the MCAP frame source takes it off again (`roadgaze.capture.mcap`).
"""

from __future__ import annotations

import logging
import queue
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import foxglove
import numpy as np
import numpy.typing as npt

from roadgaze import __version__
from roadgaze.config import Config
from roadgaze.errors import RoadgazeError
from roadgaze.outputs.foxglove.channels import FrameChannels, encode_image
from roadgaze.outputs.foxglove.targets import Target
from roadgaze.types import Alert, ClosesOnExit, Frame, FrameRecord, Sink

log = logging.getLogger(__name__)

IMAGES_WAITING = 2
"""Camera frames waiting for the image thread at most; a newer one is dropped (and counted)."""
PUT_WAIT_S = 0.5
WRITE_BATCH_S = 0.1
"""The writer thread takes what was queued this long after the first item, in one go: Python
run warm on a batch costs about a third of the same work woken frame by frame (the caches,
docs/pipeline.md), and the loop's thread is interrupted once per batch, not once per frame. The
live view shows a frame at most this late."""
IMAGE_NICENESS = 10
_STOP = object()


@dataclass(frozen=True, slots=True)
class _FrameItem:
    record: FrameRecord
    stamp_ns: int
    width_px: int
    with_image: bool


@dataclass(frozen=True, slots=True)
class _AlertItem:
    alert: Alert
    stamp_ns: int


@dataclass(frozen=True, slots=True)
class _LogItem:
    entry: logging.LogRecord
    message: str
    stamp_ns: int


class _LogTap(logging.Handler):
    """roadgaze's log lines into the recording (never blocks: a line finding the queue full is
    dropped and counted)."""

    def __init__(self, recorder: FoxgloveRecorder) -> None:
        super().__init__(logging.INFO)
        self._recorder = recorder

    def emit(self, record: logging.LogRecord) -> None:
        self._recorder.queue_log(record)


class FoxgloveRecorder(ClosesOnExit, Sink):
    """Pipeline sink: each record to `targets` (see the module doc). A context manager.

    `images`: take camera frames at all (each target still says whether it wants them now).
    `wall_clock_stamps`: stamp on the wall clock (`run`) instead of the source's timeline.
    `state`: the service's state message (`Health.state_json`), recorded every
    `state_interval_s`. `strict`: a failed write raises `RoadgazeError` in the loop (a replay);
    otherwise it is logged once and recording stops while monitoring goes on (the daemon).
    """

    def __init__(
        self,
        targets: Sequence[Target],
        config: Config,
        *,
        images: bool,
        source: str,
        wall_clock_stamps: bool = False,
        state: Callable[[], bytes] | None = None,
        strict: bool = True,
        block_on_images: bool = False,
    ) -> None:
        self.config = config
        self.settings = config.record
        self.targets = tuple(targets)
        self.images = images
        self.source = source
        self.strict = strict
        self.block_on_images = block_on_images
        self._wall_clock_stamps = wall_clock_stamps
        self._state = state
        self._context = foxglove.Context()
        self._channels = FrameChannels(
            self._context,
            config.monitor,
            config.zenoh.vehicle_id,
            limits_interval_ns=round(self.settings.state_interval_s * 1e9),
        )
        self._lock = threading.Lock()
        self._records: queue.Queue[Any] = queue.Queue(maxsize=self.settings.queue_frames)
        self._images: queue.Queue[Any] = queue.Queue(maxsize=IMAGES_WAITING)
        self._offset_ns: int | None = None
        self._last_stamp_ns = 0
        self._next_image_t_s = -float("inf")
        self._failure: RoadgazeError | None = None
        self._next_state_ns = -(2**63)
        self._closed = False
        self.records_queued = 0
        self.records_written = 0
        self.images_written = 0
        self.images_dropped = 0
        self.logs_dropped = 0
        self.waits = 0
        self.writer_cpu_s = 0.0
        """CPU time of the writer thread (records, annotations, alerts, state, logs, flushes)."""
        self.image_cpu_s = 0.0
        """CPU time of the image thread (scaling, encoding and logging the camera frames)."""
        opened: list[Target] = []
        try:
            for target in self.targets:
                target.open(self._context)
                opened.append(target)
        except BaseException:
            for target in reversed(opened):
                target.close()
            raise
        self._writer = threading.Thread(
            target=self._write_loop, name="roadgaze-record", daemon=True
        )
        self._encoder = threading.Thread(
            target=self._image_loop, name="roadgaze-images", daemon=True
        )
        self._writer.start()
        self._encoder.start()
        self._tap = _LogTap(self)
        logging.getLogger("roadgaze").addHandler(self._tap)

    # -- the loop's thread ----------------------------------------------------------------

    def on_record(self, record: FrameRecord, frame: Frame) -> None:
        if self._failure is not None and self.strict:
            raise self._failure
        offset_ns = self._offset_ns if self._offset_ns is not None else self._start(record.t_s)
        stamp_ns = offset_ns + round(record.t_s * 1e9)
        self._last_stamp_ns = stamp_ns
        with_image = self.images and self._image_due(record.t_s) and self._images_wanted()
        if with_image:
            with_image = self._put_image(frame.image, stamp_ns, record)
        self._put(self._records, _FrameItem(record, stamp_ns, frame.image.shape[1], with_image))
        self.records_queued += 1

    def on_alert(self, alert: Alert) -> None:
        """An alert raised outside the frame loop, on the alerts channel: stamped now (wall
        clock), or at its time on the source's timeline."""
        offset_ns = self._offset_ns or 0
        stamp_ns = time.time_ns() if self._wall_clock_stamps else offset_ns + round(alert.t_s * 1e9)
        self._put(self._records, _AlertItem(alert, max(0, stamp_ns)))

    def _start(self, t_s: float) -> int:
        """At the first frame: the time offset, and the metadata that carries it written ahead
        of any message (a reader of a file cut short meets it first)."""
        wall = self._wall_clock_stamps
        offset_ns = self._offset_ns = time.time_ns() - round(t_s * 1e9) if wall else 0
        metadata = self._metadata()
        with self._lock:
            try:
                for target in self.targets:
                    target.describe(metadata)
            except Exception as exc:
                self._fail(exc)
        return offset_ns

    def _image_due(self, t_s: float) -> bool:
        if t_s + 1e-6 < self._next_image_t_s:
            return False
        period_s = 1.0 / self.settings.image_fps
        following = self._next_image_t_s + period_s
        self._next_image_t_s = following if following > t_s else t_s + period_s
        return True

    def _images_wanted(self) -> bool:
        return any(target.images_wanted() for target in self.targets)

    def _put_image(self, image: npt.NDArray[np.uint8], stamp_ns: int, record: FrameRecord) -> bool:
        if self.block_on_images:
            return self._put(self._images, (image, stamp_ns, record))
        try:
            self._images.put_nowait((image, stamp_ns, record))
        except queue.Full:
            self.images_dropped += 1
            return False
        return True

    def _put(self, target: queue.Queue[Any], item: Any) -> bool:
        """Queue `item`, waiting while the queue is full (never dropped) unless recording has
        stopped on an error."""
        while True:
            if self._failure is not None and not self.strict:
                return False
            try:
                target.put(item, timeout=PUT_WAIT_S)
                return True
            except queue.Full:
                self.waits += 1
                if self.waits == 1:
                    log.warning("record: the writer is behind; the loop waits for it")

    def queue_log(self, entry: logging.LogRecord) -> None:
        """A log line into the recording, from any thread; never waits."""
        try:
            message = entry.getMessage()
            stamp_ns = self._last_stamp_ns
            if self._offset_ns is None:  # before the first frame
                stamp_ns = time.time_ns() if self._wall_clock_stamps else 0
            self._records.put_nowait(_LogItem(entry, message, stamp_ns))
        except queue.Full:
            self.logs_dropped += 1
        except Exception:  # a bad log call must not break the caller
            self.logs_dropped += 1

    # -- the writer and image threads ----------------------------------------------------

    def _metadata(self) -> Mapping[str, Mapping[str, str]]:
        config = {
            name: getattr(self.config, name).model_dump_json()
            for name in type(self.config).model_fields
        }
        return {
            "roadgaze": {
                "version": __version__,
                "source": self.source,
                "vehicle_id": self.config.zenoh.vehicle_id,
                "time_base": "wall clock" if self._wall_clock_stamps else "source",
                "time_offset_ns": str(self._offset_ns or 0),
            },
            "roadgaze.config": config,
        }

    def _next_batch(self) -> tuple[list[Any], bool]:
        """The items queued: waits for the first (at most `flush_s`), then `WRITE_BATCH_S`
        more, and takes all; True once the stop was among them."""
        try:
            items = [self._records.get(timeout=self.settings.flush_s)]
        except queue.Empty:
            return [], False
        if items[0] is not _STOP:
            time.sleep(WRITE_BATCH_S)
        while items[-1] is not _STOP:
            try:
                items.append(self._records.get_nowait())
            except queue.Empty:
                break
        stopping = items[-1] is _STOP
        return (items[:-1] if stopping else items), stopping

    def _write_loop(self) -> None:
        started_cpu_s = time.thread_time()
        next_tick_s = time.monotonic() + self.settings.flush_s
        stopping = False
        while not stopping:
            items, stopping = self._next_batch()
            if self._failure is not None:
                continue
            try:
                with self._lock:
                    for item in items:
                        self._write(item)
                    now_s = time.monotonic()
                    if now_s >= next_tick_s:
                        next_tick_s = now_s + self.settings.flush_s
                        for target in self.targets:
                            target.tick(now_s)
            except Exception as exc:
                self._fail(exc)
        self.writer_cpu_s = time.thread_time() - started_cpu_s

    def _write(self, item: Any) -> None:
        if isinstance(item, _LogItem):
            self._channels.log_line(item.entry, item.message, item.stamp_ns)
            return
        if isinstance(item, _AlertItem):
            self._channels.log_alert(item.alert, item.stamp_ns, time.time())
            return
        self._write_frame(item)
        if self._state is not None and item.stamp_ns >= self._next_state_ns:
            self._channels.log_state(self._state(), item.stamp_ns)
            self._next_state_ns = item.stamp_ns + round(self.settings.state_interval_s * 1e9)

    def _write_frame(self, item: _FrameItem) -> None:
        scale = min(1.0, self.settings.image_width_px / max(1, item.width_px))
        landmarks = self.settings.landmarks
        channels = self._channels
        channels.log_frame(
            item.record, item.stamp_ns, item.with_image, scale, landmarks, time.time()
        )
        self.records_written += 1

    def _image_loop(self) -> None:
        from roadgaze.threads import lower_this_thread_priority

        lower_this_thread_priority(IMAGE_NICENESS)
        started_cpu_s = time.thread_time()
        settings = self.settings
        while (item := self._images.get()) is not _STOP:
            if self._failure is not None:
                continue
            image, stamp_ns, record = item
            try:
                data = encode_image(
                    image, settings.image_width_px, settings.image_format, settings.jpeg_quality
                )
                with self._lock:
                    self._channels.log_driver(
                        record, image.shape, settings.image_width_px, stamp_ns
                    )
                    self._channels.log_image(data, settings.image_format, stamp_ns)
                self.images_written += 1
            except Exception as exc:
                self._fail(exc)
        self.image_cpu_s = time.thread_time() - started_cpu_s

    def _fail(self, exc: Exception) -> None:
        if self._failure is not None:
            return
        text = str(exc) if isinstance(exc, RoadgazeError) else f"{type(exc).__name__}: {exc}"
        self._failure = exc if isinstance(exc, RoadgazeError) else RoadgazeError(text)
        if not self.strict:
            log.error("record: recording stopped (monitoring goes on): %s", text)

    # -- the end -------------------------------------------------------------------------

    @property
    def failure(self) -> RoadgazeError | None:
        """Why recording stopped, if it did."""
        return self._failure

    def problem(self) -> str | None:
        """For the service's state: the recording stopped, and why (None while it works)."""
        return None if self._failure is None else f"recording stopped: {self._failure}"

    def close(self) -> None:
        """Write what is queued, close every target (an MCAP file complete and indexed) and stop
        the threads; raises the write error of a strict recorder."""
        if self._closed:
            return
        self._closed = True
        logging.getLogger("roadgaze").removeHandler(self._tap)
        self._images.put(_STOP)
        self._encoder.join()
        self._records.put(_STOP)
        self._writer.join()
        with self._lock:
            if self._state is not None and self._failure is None and self.records_written:
                try:
                    self._channels.log_state(self._state(), self._last_stamp_ns)
                except Exception as exc:
                    self._fail(exc)
            for target in self.targets:
                try:
                    target.close()
                except Exception as exc:
                    self._fail(exc)
        if self.images_dropped or self.logs_dropped:
            log.info(
                "record: %d camera frames and %d log lines dropped (the writer was busy)",
                self.images_dropped,
                self.logs_dropped,
            )
        if self._failure is not None and self.strict:
            raise self._failure
