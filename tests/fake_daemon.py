"""`roadgaze run` in a child process with a scripted camera and detector (no MediaPipe).

    python tests/fake_daemon.py [--frame-s S] [--slow-del S] RUN_ARGUMENTS...

Everything but the camera and the landmark model is real: signals, the Zenoh link, the monitor,
health and the final state. The face looks at the road for 1 s, then 30 deg to the right (zone
away) for 5 s, over and over (a long-distraction alert and its clear every 6 s); each frame takes
`--frame-s` (default 1/30 s), so a test can make a frame long enough to signal twice during it;
`--slow-del S` makes the detector's finaliser take S seconds (as MediaPipe's
`FaceLandmarker.__del__` can), so a second signal can land inside it.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))

import numpy as np

from fakes import face_at
from roadgaze.capture import SourceInfo, SourceStatus
from roadgaze.types import ClosesOnExit, Detection, Frame

FPS = 30.0


class EndlessSource(ClosesOnExit):
    """A live source of blank frames at 30 fps until closed."""

    def __init__(self) -> None:
        self._closed = False
        self._delivered = 0

    @property
    def info(self) -> SourceInfo:
        return SourceInfo("fake-camera", True, FPS, None, 64, 48)

    @property
    def status(self) -> SourceStatus:
        return SourceStatus(frames_delivered=self._delivered)

    def __iter__(self) -> Iterator[Frame]:
        while not self._closed:
            self._delivered += 1
            yield Frame(self._delivered, self._delivered / FPS, np.zeros((48, 64, 3), np.uint8))

    def close(self) -> None:
        self._closed = True


class GlancingDetector:
    """1 s on the road, 5 s at -30 deg (away), repeated; each call takes `frame_s` of wall time."""

    def __init__(self, frame_s: float) -> None:
        self.frame_s = frame_s

    def detect(self, image: Any, t_s: float | None = None) -> Detection:
        time.sleep(self.frame_s)
        yaw_deg = 0.0 if (t_s or 0.0) % 6.0 < 1.0 else -30.0
        return Detection(faces=(face_at(yaw_deg),), driver_index=0)

    def close(self) -> None:
        return None


class SlowFinalisedDetector(GlancingDetector):
    """A detector whose `__del__` takes `del_s` seconds."""

    def __init__(self, frame_s: float, del_s: float) -> None:
        super().__init__(frame_s)
        self.del_s = del_s

    def __del__(self) -> None:
        time.sleep(self.del_s)


def main(argv: list[str]) -> int:
    import roadgaze.capture
    import roadgaze.pipeline
    from roadgaze.cli import main as roadgaze_main

    frame_s, del_s = 1.0 / FPS, 0.0
    if argv[:1] == ["--frame-s"]:
        frame_s, argv = float(argv[1]), argv[2:]
    if argv[:1] == ["--slow-del"]:
        del_s, argv = float(argv[1]), argv[2:]
    roadgaze.pipeline.create_detector = lambda config: (  # type: ignore[assignment]
        SlowFinalisedDetector(frame_s, del_s) if del_s else GlancingDetector(frame_s)
    )
    roadgaze.capture.open_source = lambda *args, **kwargs: EndlessSource()  # type: ignore[assignment]
    return roadgaze_main(["run", "--source", "fake-camera", *argv])


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
