"""roadgaze's pipeline inside your own Python process: a video in, one record per frame out.

    python docs/examples/pipeline.py [VIDEO]

Without VIDEO it first renders a 9 s synthetic drive (a face that looks into the lap for 4 s,
with its exact truth beside it) into a temporary folder. Then the same stages `roadgaze replay`
and `roadgaze run` use, in this process and without Zenoh: capture -> MediaPipe landmarks ->
yaw and pitch -> Kalman smoothers -> the inattention monitor. It prints every alert as the
monitor raises it and a summary at the end. Needs only `pip install roadgaze`; the face
landmarker model is fetched on first use (`roadgaze model fetch`).

Yaw > 0: the head turned to the driver's own left (ISO 8855); pitch > 0: looking up. No speed
source is given, so the speed is unknown, which counts as moving: alerts are not suppressed.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

from roadgaze.config import load_config
from roadgaze.pipeline import RunOptions, build_run
from roadgaze.synth import render_clip
from roadgaze.types import Alert, Frame, FrameRecord, Sink

DRIVE = "0:2,0/-35:4,0:3"
"""2 s on the road, 4 s into the lap (yaw 0, pitch -35 deg), 3 s back on the road."""


class AlertPrinter(Sink):
    """A sink: `on_record` gets every frame's record in order, `on_alert` an alert raised outside
    the frame loop (a camera gone, a model that cannot be loaded), `close` once at the end."""

    def __init__(self) -> None:
        self.frames = 0
        self.faces = 0
        self.alerts: list[str] = []
        self.min_pitch_deg = float("inf")

    def on_record(self, record: FrameRecord, frame: Frame) -> None:
        self.frames += 1
        sample = record.sample
        if sample.face and sample.pitch_deg is not None:
            self.faces += 1
            self.min_pitch_deg = min(self.min_pitch_deg, sample.pitch_deg)
        for alert in record.alerts:
            self.alerts.append(alert.label)
            print(
                f"t={record.t_s:5.2f} s  ALERT {alert.kind.value} {alert.level.value}  "
                f"zone={record.verdict.zone}  off road {alert.off_road_s:.2f} s",
                flush=True,
            )

    def on_alert(self, alert: Alert) -> None:
        self.alerts.append(alert.label)
        print(f"t={alert.t_s:5.2f} s  ALERT {alert.kind.value}: {alert.reason}", flush=True)

    def close(self) -> None:
        pass


def run(video: Path) -> AlertPrinter:
    """Every frame of `video` through the pipeline; returns the sink with what it saw."""
    config = load_config()  # defaults < ROADGAZE__SECTION__FIELD environment variables
    printer = AlertPrinter()
    # The run as `roadgaze replay` builds it: the video, the detector, the monitor, our sink.
    with build_run(config, RunOptions(str(video), command="example"), sinks=(printer,)) as run:
        summary = run.run()
    print(
        f"{summary.frames} frames, a face in {summary.frames_with_face}, "
        f"in {summary.wall_s:.1f} s; lowest smoothed pitch {printer.min_pitch_deg:.1f} deg; "
        f"alerts: {', '.join(printer.alerts) or 'none'}"
    )
    return printer


def main(argv: list[str]) -> int:
    if len(argv) > 1:
        run(Path(argv[1]))
        return 0
    with tempfile.TemporaryDirectory(prefix="roadgaze-example-") as folder:
        video = Path(folder) / "drive.mkv"
        print(f"rendering the drive {DRIVE!r} to {video}", flush=True)
        render_clip(DRIVE, video, size=(320, 320))
        run(video)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv))
