"""`roadgaze demo`: a synthetic drive through the whole service, with a Zenoh subscriber watching.

One run, no camera and no video needed: the astronaut photo (or `photo`) is turned through a short
drive (road, one long look into the lap, a few short glances, road again) by `roadgaze.synth`;
the service (`roadgaze.pipeline.build_run`, as `run` builds it: landmarks, full-range yaw,
pitch, smoother, monitor with zones, Zenoh publisher on 127.0.0.1) runs over the clip as fast as
it can; a second Zenoh session,
connected to the first over loopback, subscribes to the alert key and reports each alert as it
arrives. The output folder then holds the clip and its truth, the per-frame records, the received
alerts, a plot and the annotated video.
"""

from __future__ import annotations

import json
import logging
import math
import socket
import threading
import time
from collections.abc import Callable
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from roadgaze.config import Config
from roadgaze.errors import RoadgazeError
from roadgaze.synth import Timeline, parse_timeline, truth_path_for, write_truth_csv

log = logging.getLogger(__name__)

DRIVE_TIMELINE = "0:3,0/-35:5,0:2,-35:1.5,0:1.5,35:1.5,0:1.5,-45:1.5,0:1.5,30:1.5,0:3"
"""Road 3 s; a 5 s look down into the lap (a long-distraction alert); four 1.5 s glances (to the
right, the left mirror, the right mirror, the left mirror) that push the off-road time in the
last 30 s over 10 s (a VATS alert: mirror glances count); back to the road (cleared).
(Before zones the long glance went 40 deg to the left, which is now the left mirror.)"""
DEMO_FPS = 15.0
DEMO_SIZE = (640, 480)
SUBSCRIBER_WAIT_S = 10.0
"""How long to wait for the subscriber to see the publisher, and for the last alerts to arrive."""

VIDEO_NAME = "drive.mp4"
TRUTH_NAME = "truth.csv"
FRAMES_NAME = "frames.jsonl"
ALERTS_NAME = "alerts.jsonl"
PLOT_NAME = "yaw.png"
ANNOTATED_NAME = "annotated.mp4"


@dataclass(frozen=True, slots=True)
class DemoResult:
    """What a demo run produced, and how long its parts took."""

    out_dir: Path
    frames: int
    frames_with_face: int
    alerts_raised: int
    alerts_received: tuple[dict[str, Any], ...]
    """The alert messages as the subscriber decoded them, in arrival order."""
    render_s: float
    service_s: float
    total_s: float
    yaw_mae_deg: float
    """Mean |smoothed yaw - truth| over the frames with a smoothed yaw."""
    files: tuple[Path, ...]


def free_local_port() -> int:
    """A TCP port on 127.0.0.1 that is free right now (for the demo's own Zenoh listener)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        probe.bind(("127.0.0.1", 0))
        port: int = probe.getsockname()[1]
        return port


def demo_config(base: Config, port: int) -> Config:
    """`base` with the demo's Zenoh settings: a peer listening on 127.0.0.1:`port`, no scouting."""
    zenoh = base.zenoh.model_copy(
        update={
            "mode": "peer",
            "listen": [f"tcp/127.0.0.1:{port}"],
            "connect": [],
            "multicast_scouting": False,
            "config_file": None,
        }
    )
    return base.model_copy(update={"zenoh": zenoh})


def subscriber_config(config: Config, port: int) -> Config:
    """A peer that listens nowhere and connects to the demo's publisher on 127.0.0.1:`port`."""
    zenoh = config.zenoh.model_copy(
        update={"mode": "peer", "listen": [], "connect": [f"tcp/127.0.0.1:{port}"]}
    )
    return config.model_copy(update={"zenoh": zenoh})


class AlertSubscriber:
    """A Zenoh subscriber to the alert key in its own session; appends each alert to a file.

    `on_alert` is called from the receiving thread with each decoded message, in arrival order.
    """

    def __init__(
        self,
        config: Config,
        alerts_path: Path,
        on_alert: Callable[[dict[str, Any]], None],
    ) -> None:
        from roadgaze.transport import Subscription

        self._on_alert = on_alert
        self._lock = threading.Lock()
        self.received: list[dict[str, Any]] = []
        self._file = alerts_path.open("w", encoding="utf-8")
        try:
            self._subscription = Subscription(config, lambda keys: keys.alert, self._on_sample)
        except BaseException:
            self._file.close()
            raise

    def _on_sample(self, sample: Any) -> None:
        raw = sample.payload.to_bytes()
        try:
            message = json.loads(raw)
        except ValueError:
            message = {"undecodable": raw.decode("utf-8", "replace")}
        with self._lock:
            if self._file.closed:
                return
            self.received.append(message)
            self._file.write(json.dumps(message) + "\n")
            self._file.flush()
        self._on_alert(message)

    def wait_for_publisher(self, timeout_s: float) -> bool:
        """True once the publisher's liveliness token is visible (routes are then in place)."""
        return self._subscription.wait_for_publisher(timeout_s)

    def wait_for_count(self, count: int, timeout_s: float) -> bool:
        """True once `count` alerts have arrived; False after `timeout_s`."""

        def arrived() -> bool:
            with self._lock:
                return len(self.received) >= count

        return self._subscription.wait_until(arrived, timeout_s)

    def close(self) -> None:
        self._subscription.close()
        with self._lock:
            self._file.close()


def format_alert(message: dict[str, Any]) -> str:
    """One line for an alert message as received."""
    if "kind" not in message:
        return f"subscriber: undecodable alert {message}"
    yaw = message.get("yaw_deg")
    yaw_text = "no face" if yaw is None else f"yaw {yaw:+.1f} deg"
    return (
        f"subscriber received alert #{message.get('seq')}: {message.get('kind')} "
        f"{message.get('level')} at t={message.get('t_s', 0.0):.2f} s "
        f"(off road {message.get('off_road_s', 0.0):.2f} s, "
        f"{message.get('window_off_road_s', 0.0):.2f} s in the window; {yaw_text})"
    )


def fetch_hand_models_for_demo(config: Config, progress: Callable[[str], None]) -> None:
    """The demo is a first run on a fresh machine: it fetches the hand models (as `roadgaze model
    fetch hands`) so that it shows the whole service. The daemon never downloads them at start-up
    (docs/phone.md); where they cannot be had, the demo runs without phone detection and the hand
    stage says so."""
    from roadgaze.errors import ModelError
    from roadgaze.landmarks.hands.models import MODEL_FILES, fetch_hand_models, find_hand_models

    if not (config.hands.enabled and config.model.allow_download):
        return
    _, missing = find_hand_models(config.model, tuple(MODEL_FILES))
    if not missing:
        return
    progress("fetching the hand models (roadgaze model fetch hands)")
    try:
        fetch_hand_models(config.model)
    except ModelError as exc:
        log.info("the demo runs without phone detection: %s", exc)


def run_demo(
    out_dir: Path,
    config: Config | None = None,
    photo: Path | None = None,
    timeline: Timeline | None = None,
    fps: float = DEMO_FPS,
    size: tuple[int, int] = DEMO_SIZE,
    on_alert: Callable[[dict[str, Any]], None] | None = None,
    on_progress: Callable[[str], None] | None = None,
) -> DemoResult:
    """Render the drive, run the service over it with a subscriber, write everything to `out_dir`.

    Raises RoadgazeError (ModelError, SourceError, TransportError ...) with a clear message; what
    was written before an error stays in `out_dir`.
    """
    from roadgaze.outputs import YawPlot, fill_offline_columns
    from roadgaze.pipeline import RunOptions, build_run
    from roadgaze.synth import FaceRenderer, load_photo, render_clip

    started = time.perf_counter()
    progress = on_progress if on_progress is not None else (lambda text: None)
    on_alert = on_alert if on_alert is not None else (lambda message: None)
    config = config if config is not None else Config()
    timeline = timeline if timeline is not None else parse_timeline(DRIVE_TIMELINE)
    out_dir = Path(out_dir)
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise RoadgazeError(f"cannot create output folder {out_dir}: {exc.strerror}") from None

    progress(f"rendering a {timeline.duration_s:g} s drive at {fps:g} fps, {size[0]}x{size[1]}")
    renderer = FaceRenderer(load_photo(photo), size, config=config)
    video_path = out_dir / VIDEO_NAME
    truth = render_clip(timeline, video_path, fps=fps, renderer=renderer)
    truth_csv = out_dir / TRUTH_NAME
    write_truth_csv(truth_csv, truth)
    truth_path_for(video_path).unlink(missing_ok=True)
    rendered = time.perf_counter()

    fetch_hand_models_for_demo(config, progress)
    port = free_local_port()
    config = demo_config(config, port)
    plot_path = out_dir / PLOT_NAME
    plot = YawPlot(
        plot_path,
        title="roadgaze demo: synthetic drive",
        truth=truth,
        monitor=config.monitor,
    )
    progress(f"running the service over {VIDEO_NAME}, Zenoh on tcp/127.0.0.1:{port}")
    options = RunOptions(
        str(video_path),
        command="demo",
        publish=True,
        records=out_dir / FRAMES_NAME,
        annotate=out_dir / ANNOTATED_NAME,
    )
    with ExitStack() as stack:
        stack.enter_context(plot)
        # The subscriber closes after the service's session: a subscriber leaving first is a
        # link going down to the service, which warns that alerts are held.
        subscribers = stack.enter_context(ExitStack())
        service = stack.enter_context(build_run(config, options, sinks=(plot,)))
        subscriber = AlertSubscriber(
            subscriber_config(config, port), out_dir / ALERTS_NAME, on_alert
        )
        subscribers.callback(subscriber.close)
        if not subscriber.wait_for_publisher(SUBSCRIBER_WAIT_S):
            log.warning("the subscriber did not see the publisher within %.0f s", SUBSCRIBER_WAIT_S)
        summary = service.run()
        raised = service.health.alerts_raised
        if not subscriber.wait_for_count(raised, SUBSCRIBER_WAIT_S):
            log.warning("the subscriber received %d of %d alerts", len(subscriber.received), raised)
        received = tuple(subscriber.received)
    fill_offline_columns(out_dir / FRAMES_NAME, config.smoothing)
    served = time.perf_counter()

    smoothed = np.asarray(plot.smoothed_deg)
    count = min(len(smoothed), len(truth))
    errors = np.abs(smoothed[:count] - truth[:count, 1])
    finite = errors[np.isfinite(errors)]
    return DemoResult(
        out_dir=out_dir,
        frames=summary.frames,
        frames_with_face=summary.frames_with_face,
        alerts_raised=raised,
        alerts_received=received,
        render_s=rendered - started,
        service_s=served - rendered,
        total_s=time.perf_counter() - started,
        yaw_mae_deg=float(finite.mean()) if finite.size else math.nan,
        files=(
            out_dir / VIDEO_NAME,
            truth_csv,
            out_dir / FRAMES_NAME,
            out_dir / ALERTS_NAME,
            plot_path,
            out_dir / ANNOTATED_NAME,
        ),
    )
