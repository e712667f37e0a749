"""One home for wiring: every run's pipeline and sinks, built from the configuration and the run's
options (`RunOptions`). `run`, `replay`, `demo`, `bench`, `batch`, `conformance`, the held-out
check and the scripts all use `build_run`; nothing else assembles a pipeline and its sinks.

`build_run` opens, in this order (and closes in the reverse order):

1. the vehicle speed: a constant, a named track, the track beside the video, the bus when
   publishing, else none (taken as moving), and logs where it comes from;
2. the paths checked: no output onto a file the run reads (the source, the speed track, even
   the one found beside the video, the model, the configuration files, through symbolic or hard
   links), no output folder holding one, no two outputs on one file: one line, nothing written;
3. a file source (a bad file fails before anything is connected or written);
4. the bus (`bus_outputs`: the `Health` sink, and with `publish` the Zenoh link and its
   publishers), the recorder (`--mcap`, `--record`, `--foxglove`) and the caller's sinks;
5. the detector: a model that cannot be loaded is raised as a `permanent_failure` to every sink
   open by then (the bus, the recorder, the caller's), then the one-line error;
6. a camera (waited for with `wait_for_camera`, after the model so no frame waits for it) and,
   with `watch_failures`, the watch that raises `permanent_failure` when it stays lost;
7. the writers the options ask for (records, CSV, plot, annotated video, progress bar) and the
   speed gate's log.

Alerts raised outside the frame loop go to every sink through `Run.alert` (`Sink.on_alert`),
under the lock the loop holds while it feeds the sinks: a sink is never called twice at once.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import ExitStack, closing, contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from roadgaze.capture import FrameSource, camera_device
from roadgaze.config import Config
from roadgaze.errors import RoadgazeError
from roadgaze.pipeline.bus import BusOutputs, bus_outputs
from roadgaze.pipeline.loop import Pipeline, ProcessedFrame, StopSignal
from roadgaze.pipeline.sinks import check_paths, recorders, writers
from roadgaze.pipeline.speed_gate import SpeedGateLog
from roadgaze.pipeline.timing import RunSummary, StageTimings
from roadgaze.speed import SpeedChoice, SpeedSource, VehicleSpeed, no_speed, recorded_speed
from roadgaze.transport.failure_watch import PermanentFailureWatch, failure_alert
from roadgaze.transport.health import ALERT_LOG, Health
from roadgaze.types import Alert, Frame, FrameRecord, LandmarkDetector, Sink

log = logging.getLogger(__name__)


@dataclass(frozen=True, slots=True)
class RunOptions:
    """What one run reads and writes besides the configuration: the command line's choices."""

    source: str
    """The frame source as the user names it: a file, a folder, /dev/videoN or an index (a
    label when the caller gives the source itself)."""
    command: str = "run"
    """Names the run in its log lines (`replay drive.mp4: ...`)."""
    publish: bool = False
    """Publish on Zenoh (yaw, alerts, state, VSS); the bus's speed when no other is given."""
    speed_track: Path | None = None
    speed_kmh: float | None = None
    track_beside: bool = False
    """Take `<stem>.speed.csv` or `.speed.parquet` beside the video when no speed is given."""
    records: str | Path | None = None
    """JSON-lines records: a file, or '-' for stdout."""
    csv: Path | None = None
    plot: Path | None = None
    annotate: Path | None = None
    mcap: Path | None = None
    """A replay's MCAP recording, stamped on the source's timeline."""
    record_dir: Path | None = None
    """The vehicle's MCAP segments (wall clock), pruned to `record.max_disk_mb`."""
    foxglove: str | None = None
    """`[HOST:]PORT` of the live view."""
    progress: str | None = None
    """A progress bar on stderr with this description; None: no bar."""
    max_frames: int | None = None
    realtime: bool = False
    """Paced at the source's rate (a replay's recording then drops camera frames it cannot
    keep up with, as a live one does)."""
    wait_for_camera: bool = False
    watch_failures: bool = False
    inputs: Mapping[str, Path | None] = field(default_factory=dict)
    """Other files the run reads (`--config`), by the name used in messages."""
    quiet: bool = False
    """A tool's run (bench, batch, conformance): no health sink or alert lines unless it
    publishes; the speed's origin and gate logged at DEBUG."""

    @property
    def log_name(self) -> str:
        """The logger of the run's lines (the daemon's alerts: `roadgaze.daemon`)."""
        return ALERT_LOG if self.command == "run" else f"roadgaze.{self.command}"


class Run:
    """A built run: `run()` drives the loop over the source into every sink; `alert()` sends
    an alert raised outside the loop to every sink."""

    def __init__(
        self,
        pipeline: Pipeline,
        source: FrameSource,
        sinks: list[Sink],
        bus: BusOutputs,
        speed_origin: str,
        lock: threading.RLock,
    ) -> None:
        self.pipeline = pipeline
        self.source = source
        self._sinks = sinks
        self.bus = bus
        self.speed_origin = speed_origin
        self._lock = lock

    @property
    def sinks(self) -> tuple[Sink, ...]:
        return tuple(self._sinks)

    @property
    def health(self) -> Health:
        return self.bus.health

    def run(
        self,
        *,
        realtime: bool = False,
        max_frames: int | None = None,
        stop: StopSignal | None = None,
        timings: StageTimings | None = None,
    ) -> RunSummary:
        """`Pipeline.run` over the source into every sink (see there)."""
        sinks = (_Locked(self._sinks, self._lock),)
        return self.pipeline.run(
            self.source,
            sinks,
            realtime=realtime,
            max_frames=max_frames,
            stop=stop,
            timings=timings,
        )

    def frames(
        self, *, realtime: bool = False, max_frames: int | None = None
    ) -> Iterator[ProcessedFrame]:
        """The loop as an iterator (`Pipeline.frames`): each frame is yielded after every sink
        has had its record, e.g. to keep the records of a short clip."""
        sinks = _Locked(self._sinks, self._lock)
        loop = self.pipeline.frames(self.source, realtime=realtime, max_frames=max_frames)
        with closing(loop):
            for processed in loop:
                sinks.on_record(processed.record, processed.frame)
                yield processed

    def alert(self, alert: Alert) -> None:
        """`alert` to every sink's `on_alert`; one that fails does not keep it from the others
        (its error is raised after all had it)."""
        deliver(self._sinks, self._lock, alert)

    def undelivered(self) -> int:
        """Alerts that never reached the bus (after the run's block: the final count)."""
        return self.bus.undelivered()


def deliver(sinks: Sequence[Sink], lock: threading.RLock, alert: Alert) -> None:
    """`alert` to every sink in `sinks` under `lock`; the first error is raised after all."""
    failed: Exception | None = None
    with lock:
        for sink in sinks:
            try:
                sink.on_alert(alert)
            except Exception as exc:
                log.warning(
                    "%s could not take the %s alert: %s", type(sink).__name__, alert.kind, exc
                )
                failed = failed or exc
    if failed is not None:
        raise failed


class _Locked(Sink):
    """The run's sinks as one, fed under the lock `Run.alert` takes."""

    def __init__(self, sinks: Sequence[Sink], lock: threading.RLock) -> None:
        self._sinks, self._lock = sinks, lock

    def on_record(self, record: FrameRecord, frame: Frame) -> None:
        with self._lock:
            for sink in self._sinks:
                sink.on_record(record, frame)

    def close(self) -> None:
        return None


def choose_speed(config: Config, options: RunOptions) -> SpeedChoice:
    """The recorded drive's speed the options name (a constant, a named track, or the track
    beside the video with `track_beside`), read as `replay` reads it; the speed is None when
    there is none (the bus's, or unknown)."""
    video = options.source if options.track_beside else None
    return recorded_speed(
        video,
        options.speed_track,
        options.speed_kmh,
        config.zenoh.speed_timeout_s,
        max_rows=config.capture.speed_track_max_rows,
    )


def _speed_for(
    options: RunOptions, choice: SpeedChoice, bus: BusOutputs, config: Config
) -> tuple[VehicleSpeed | SpeedSource, str]:
    """The speed the monitor uses and where it comes from (for the log)."""
    if choice.speed is not None:  # a recorded drive's own speed wins over the bus
        return choice.speed, f"vehicle speed from {choice.origin}"
    if options.publish and bus.speed is not no_speed:
        key = config.zenoh.speed_key.format(vehicle_id=config.zenoh.vehicle_id)
        return bus.speed, f"vehicle speed from the bus ({key}; unknown until a valid one comes)"
    why = " (zenoh.speed_key is empty)" if options.publish else ""
    return no_speed, f"no vehicle speed{why}: taken as moving"


def is_camera(spec: str) -> bool:
    """`spec` names a camera (`/dev/videoN` or an index) and no file or folder."""
    return not Path(spec).expanduser().exists() and camera_device(spec) is not None


@contextmanager
def build_run(
    config: Config,
    options: RunOptions,
    *,
    source: FrameSource | None = None,
    detector: LandmarkDetector | None = None,
    sinks: Sequence[Sink] = (),
    first_sinks: Sequence[Sink] = (),
    on_step: Callable[[str], None] | None = None,
) -> Iterator[Run]:
    """The run the options describe, opened in the order of the module doc; everything is
    closed on the way out. A `source` or `detector` given is used (and closed) instead of
    opening `options.source` and the configured landmarker; `sinks` come after the built ones,
    `first_sinks` before them. `on_step` hears each start-up step (systemd's status)."""
    from roadgaze import capture, pipeline

    every = [*first_sinks, *sinks]
    for sink in every:
        if not callable(getattr(sink, "on_alert", None)):
            raise TypeError(f"{type(sink).__name__} has no on_alert: subclass roadgaze.types.Sink")
    step = on_step if on_step is not None else (lambda text: None)
    lock = threading.RLock()
    run_sinks: list[Sink] = list(first_sinks)
    level = logging.DEBUG if options.quiet else logging.INFO
    with ExitStack() as stack:
        choice = choose_speed(config, options)
        check_paths(config, options, choice)
        if source is not None:
            source = stack.enter_context(source)
        elif not is_camera(options.source):
            source = stack.enter_context(capture.open_source(options.source, config))
        ending = (
            "the daemon stopped" if options.command == "run" else f"the {options.command} ended"
        )
        bus = stack.enter_context(
            bus_outputs(
                config, options.source, options.publish, log_name=options.log_name, ending=ending
            )
        )
        if options.publish or not options.quiet:
            run_sinks.extend(bus.sinks)
        run_sinks.extend(recorders(config, options, bus, source, stack))
        run_sinks.extend(sinks)
        step("loading the face landmarker model")
        if detector is None:
            try:
                detector = pipeline.create_detector(config)
            except RoadgazeError as exc:  # told on the bus (and recorded) before the error
                deliver(run_sinks, lock, failure_alert(0.0, f"model unusable: {exc}"))
                raise
        stack.enter_context(closing(detector))
        if source is None:
            step(f"opening {options.source}")
            source = stack.enter_context(
                capture.open_source(options.source, config, wait_for_camera=options.wait_for_camera)
            )
        bus.health.source = source
        speed, origin = _speed_for(options, choice, bus, config)
        built = Run(
            Pipeline.from_config(config, detector, speed=speed),
            source,
            run_sinks,
            bus,
            origin,
            lock,
        )
        if options.watch_failures:
            limit_s = config.monitor.permanent_failure_s
            stack.callback(PermanentFailureWatch(bus.health, built.alert, limit_s).start().close)
        run_sinks.extend(writers(config, options, source, stack))
        label = f"{options.command} {options.source}"
        gate = SpeedGateLog(options.log_name, label, level=level)
        stack.callback(gate.close)
        run_sinks.append(gate)
        logging.getLogger(options.log_name).log(level, "%s: %s", label, origin)
        yield built
