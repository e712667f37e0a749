"""The shared fakes of the swappable edges: camera, detector, frame source and message link.

Also `record_of`, a frame record around a pose sample as the monitor would leave it with no
history (for writer and publisher tests).
"""

from __future__ import annotations

import os
import socket
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from roadgaze.capture import SourceInfo, SourceStatus
from roadgaze.config import MonitorConfig
from roadgaze.monitor import initial_state, verdict_of
from roadgaze.pose.geometry import forward_model
from roadgaze.transport import AlertMessage, SpeedInput, TransportStatus, YawMessage
from roadgaze.transport.support_message import SupportMessage
from roadgaze.types import (
    Alert,
    ClosesOnExit,
    Detection,
    EyeMeasurement,
    EyesFeatures,
    FaceFeatures,
    Frame,
    FrameRecord,
    PoseSample,
    Verdict,
)


def numbered_image(index: int, size: tuple[int, int] = (160, 120)) -> np.ndarray:
    """A grey image with its number drawn on it, so frames can be told apart."""
    width, height = size
    image = np.full((height, width, 3), (index * 7) % 256, np.uint8)
    cv2.putText(image, str(index), (10, 80), cv2.FONT_HERSHEY_SIMPLEX, 2, (255, 255, 255), 3)
    return image


class FakeCamera:
    """Stands in for `cv2.VideoCapture(device, CAP_V4L2)`.

    Serves `frames` reads (None: without end; then every read fails, as if unplugged), one every
    `period_s`: copies of `image`, or numbered images. `opened=False` is a device that cannot be
    opened. Settings and the release are appended to `log`.
    """

    def __init__(
        self,
        frames: int | None = None,
        *,
        image: np.ndarray | None = None,
        opened: bool = True,
        period_s: float = 0.002,
        log: list[Any] | None = None,
    ) -> None:
        self.frames_left = frames
        self.image = image
        self.opened = opened
        self.period_s = period_s
        self.log = log if log is not None else []
        self.served = 0

    def isOpened(self) -> bool:  # noqa: N802 (OpenCV's name)
        return self.opened

    def read(self) -> tuple[bool, Any]:
        time.sleep(self.period_s)  # a camera paces its frames; keeps the fake from spinning
        if self.frames_left is not None:
            if self.frames_left <= 0:
                return False, None
            self.frames_left -= 1
        self.served += 1
        return True, numbered_image(self.served) if self.image is None else self.image.copy()

    def get(self, prop_id: int) -> float:
        if self.image is not None:
            return 0.0
        return {cv2.CAP_PROP_FRAME_WIDTH: 640.0, cv2.CAP_PROP_FRAME_HEIGHT: 480.0}.get(prop_id, 0.0)

    def set(self, prop_id: int, value: float) -> bool:
        self.log.append((prop_id, value))
        return True

    def release(self) -> None:
        self.log.append("release")


def eyes_of(
    openness: float = 0.30,
    blink: float | None = None,
    eye_yaw: float = 0.0,
    eye_pitch: float = 0.0,
    usable: bool = True,
    occluded: bool = False,
) -> EyesFeatures:
    """Both eyes alike: `openness` (lid gap / eye width), eyeBlink `blink` (None: 0.6 below
    0.14, else 0.05), eye-in-head direction; `usable` False: a turned head (no eye)."""
    if blink is None:
        blink = 0.6 if openness < 0.14 else 0.05

    def one(side: str) -> EyeMeasurement:
        return EyeMeasurement(
            side=side,
            width_px=30.0,
            openness=openness,
            gaze_usable=usable and not occluded,
            closure_usable=usable and not occluded,
            reason="" if usable else "head turned",
            yaw_deg=eye_yaw if usable else None,
            pitch_deg=eye_pitch if usable else None,
            blink=blink,
            look_down=0.0,
        )

    return EyesFeatures(
        right=one("right"),
        left=one("left"),
        method="blendshapes",
        scale_px=30.0,
        reason="" if usable else "head turned",
        occluded=occluded,
    )


def open_eyes(openness: float = 0.3, direction: bool = False) -> EyesFeatures:
    """Both eyes open and judged; with `direction`, looking straight ahead (eye yaw and pitch 0),
    else giving no direction, so the monitor judges the zone on the head pose alone."""

    def eye(side: str) -> EyeMeasurement:
        return EyeMeasurement(
            side=side,
            width_px=30.0,
            openness=openness,
            gaze_usable=direction,
            closure_usable=True,
            yaw_deg=0.0 if direction else None,
            pitch_deg=0.0 if direction else None,
            blink=0.05,
            look_down=0.0,
        )

    return EyesFeatures(right=eye("right"), left=eye("left"), method="blendshapes", scale_px=30.0)


def face_at(yaw_deg: float, pitch_deg: float | None = None) -> FaceFeatures:
    """A face whose boundaries and centre come from the paper's forward model; `pitch_deg` is
    MediaPipe's matrix pitch (None: no matrix)."""
    projected = forward_model(yaw_deg, half_width_px=80.0, pivot_x_px=320.0)
    return FaceFeatures(
        mediapipe_pitch_deg=pitch_deg,
        x_left_px=float(projected.x_left),
        x_right_px=float(projected.x_right),
        x_center_px=float(projected.x_center),
        roll_deg=0.0,
        box_px=(220.0, 140.0, 420.0, 380.0),
        quality=1.0,
        landmarks_px=np.zeros((0, 3), np.float32),
    )


class ScriptedDetector:
    """Fake `LandmarkDetector`: the true yaw per call (None: no face), checking time order;
    optionally MediaPipe's matrix pitch per call."""

    def __init__(
        self, yaws_deg: list[float | None], pitches_deg: list[float] | None = None
    ) -> None:
        self.yaws_deg = list(yaws_deg)
        self.pitches_deg = pitches_deg
        self.calls: list[float | None] = []
        self.closed = False

    def detect(self, image: np.ndarray, t_s: float | None = None) -> Detection:
        assert t_s is not None and (not self.calls or t_s > (self.calls[-1] or -1.0))
        yaw_deg = self.yaws_deg[len(self.calls)]
        self.calls.append(t_s)
        if yaw_deg is None:
            return Detection(faces=(), driver_index=None)
        pitch_deg = None if self.pitches_deg is None else self.pitches_deg[len(self.calls) - 1]
        return Detection(faces=(face_at(yaw_deg, pitch_deg),), driver_index=0)

    def close(self) -> None:
        self.closed = True


class ListSource(ClosesOnExit):
    """Fake `FrameSource` over `count` blank frames at `fps`."""

    def __init__(self, count: int, fps: float = 30.0) -> None:
        self.count, self.fps = count, fps
        self._status = SourceStatus()

    @property
    def info(self) -> SourceInfo:
        return SourceInfo("list", False, self.fps, self.count, 64, 48)

    @property
    def status(self) -> SourceStatus:
        return self._status

    def __iter__(self) -> Iterator[Frame]:
        for i in range(self.count):
            self._status = SourceStatus(frames_delivered=i + 1)
            yield Frame(index=i, t_s=i / self.fps, image=np.zeros((48, 64, 3), np.uint8))

    def close(self) -> None:
        return None


@dataclass
class FakeLink:
    """Fake `MessageLink`: keeps every message; `connected` is what its status reports."""

    yaw: list[YawMessage] = field(default_factory=list)
    alerts: list[AlertMessage] = field(default_factory=list)
    support: list[SupportMessage] = field(default_factory=list)
    connected: bool = True
    speed: SpeedInput | None = None

    def publish_yaw(self, message: YawMessage) -> None:
        self.yaw.append(message)

    def publish_alert(self, message: AlertMessage) -> None:
        self.alerts.append(message)

    def publish_support(self, message: SupportMessage) -> None:
        self.support.append(message)

    def status(self) -> TransportStatus:
        return TransportStatus(mode="peer", session_open=True, connected=self.connected)


BLANK_FRAME = Frame(0, 0.0, np.zeros((4, 4, 3), np.uint8))
"""A frame for sinks that ignore the image."""


FACE = FaceFeatures(
    x_left_px=100.0,
    x_right_px=180.0,
    x_center_px=150.0,
    roll_deg=10.0,
    box_px=(95.0, 60.0, 185.0, 170.0),
    quality=0.9,
    landmarks_px=np.array([[100, 100, 0], [180, 110, 0], [150, 160, 0]], np.float32),
)
"""A face 80 px wide with its centre right of the middle (for writer and record tests)."""


def record_of(
    sample: PoseSample, verdict: Verdict | None = None, alerts: tuple[Alert, ...] = ()
) -> FrameRecord:
    """A frame record of `sample`; the verdict defaults to the monitor's initial one."""
    if verdict is None:
        config = MonitorConfig()
        verdict = verdict_of(config, initial_state(config))
    return FrameRecord(sample=sample, verdict=verdict, alerts=alerts)


def yaw_message(seq: int, yaw_deg: float = 10.0, vehicle_id: str = "test-car") -> YawMessage:
    """A valid yaw message of one frame at 30 fps."""
    return YawMessage(
        vehicle_id=vehicle_id,
        seq=seq,
        t_s=seq / 30,
        wall_time=time.time(),
        frame=seq,
        face=True,
        yaw_deg=yaw_deg,
        yaw_raw_deg=yaw_deg,
        on_road=True,
        gaze="on_road",
        neutral_yaw_deg=0.0,
        n_faces=1,
    )


def alert_message(seq: int = 0, vehicle_id: str = "test-car") -> AlertMessage:
    """A valid long-distraction warning."""
    return AlertMessage(
        vehicle_id=vehicle_id,
        seq=seq,
        kind="long_distraction",
        level="warning",
        t_s=7.0,
        wall_time=time.time(),
        yaw_deg=45.0,
        off_road_s=3.0,
        window_off_road_s=3.0,
    )


class FakeNotifySocket:
    """Stands in for systemd's `$NOTIFY_SOCKET`: a datagram socket (a path, or an abstract name
    when `abstract`) whose messages a thread keeps as `(received monotonic s, {KEY: value})`."""

    def __init__(self, folder: Path, abstract: bool = False) -> None:
        self._socket = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
        if abstract:
            name = f"roadgaze-test-{os.getpid()}-{id(self)}"
            self._socket.bind("\0" + name)
            self.address = "@" + name
        else:
            path = folder / "notify.sock"
            self._socket.bind(str(path))
            self.address = str(path)
        self._socket.settimeout(0.1)
        self.messages: list[tuple[float, dict[str, str]]] = []
        self.raw: list[bytes] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._receive, daemon=True)
        self._thread.start()

    def _receive(self) -> None:
        while not self._stop.is_set():
            try:
                data = self._socket.recv(4096)
            except TimeoutError:
                continue
            except OSError:
                return
            self.raw.append(data)
            fields = dict(line.split("=", 1) for line in data.decode().splitlines())
            self.messages.append((time.monotonic(), fields))

    def with_key(self, key: str) -> list[tuple[float, dict[str, str]]]:
        return [(t_s, fields) for t_s, fields in list(self.messages) if key in fields]

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=2.0)
        self._socket.close()


def die_on_crash_drives(task: Any) -> Any:
    """A fleet task function for worker processes: the process dies on drives named `crash*`
    (as on a crash in native code); other drives succeed at once with one frame."""
    import os

    from roadgaze.fleet import DriveResult

    if task.drive.drive_id.startswith("crash"):
        os._exit(70)
    return DriveResult.of(task.drive, "ok", frames=1, duration_s=0.1)


def face_sample(
    t_s: float,
    frame: int,
    yaw_deg: float,
    pitch_deg: float = 0.0,
    eyes: EyesFeatures | None = None,
    face: bool = True,
    **extra: Any,
) -> PoseSample:
    """A scripted `PoseSample`: the head at `yaw_deg`, `pitch_deg` (raw and smoothed alike,
    steady, 1 deg of spread) with `eyes` when there is a `face`, nothing measured without one;
    `extra` sets any other field (`frame_check`, `phone`, `n_faces`, `driver_ambiguous`, ...)."""
    measured: dict[str, Any] = {
        "yaw_raw_deg": yaw_deg,
        "yaw_deg": yaw_deg,
        "yaw_rate_dps": 0.0,
        "yaw_std_deg": 1.0,
        "pitch_raw_deg": pitch_deg,
        "pitch_deg": pitch_deg,
        "eyes": eyes,
    }
    fields = {name: value if face else None for name, value in measured.items()}
    fields["n_faces"] = int(face)
    return PoseSample(t_s=t_s, frame=frame, face=face, **(fields | extra))


def drive_monitor(
    monitor: Any,
    pose_at: Any,
    speed_kmh: float | None,
    duration_s: float,
    fps: float = 15.0,
    frame_check_at: Any = None,
) -> list[Any]:
    """Feed `monitor` (a `Monitor`) samples at `fps`: `pose_at(t_s) -> (yaw or None for no face,
    pitch)`, open eyes with a face, `frame_check_at(t_s)` the frame's checks; the alerts raised."""
    from roadgaze.types import PoseSample

    alerts: list[Any] = []
    for frame in range(round(duration_s * fps)):
        t_s = frame / fps
        yaw, pitch = pose_at(t_s)
        face = yaw is not None
        check = None if frame_check_at is None else frame_check_at(t_s)
        sample = PoseSample(
            t_s, frame, face, yaw, yaw, 0.0, 1.0, None, int(face), pitch, pitch,
            eyes=open_eyes() if face else None, frame_check=check,
        )  # fmt: skip
        alerts.extend(monitor.update(sample, speed_kmh))
    return alerts
