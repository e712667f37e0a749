"""The driver among several faces without multi-face inference on every frame: the pure switch,
then the real MediaPipe landmarker on a stream where a second face comes and goes."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import cv2
import numpy as np
import numpy.typing as npt
import pytest
from skimage import data as skimage_data

from roadgaze.config import Config, LandmarksConfig, MonitorConfig, load_config
from roadgaze.landmarks import MediaPipeLandmarker
from roadgaze.landmarks.model_store import resolve_model
from roadgaze.landmarks.multi_face import (
    MULTI_FACE_RETURN_S,
    BackgroundCount,
    FaceMode,
    MultiFaceSwitch,
    detector_model_bytes,
)
from roadgaze.types import RecordedDriver

BOX = (100.0, 100.0, 200.0, 220.0)
MOVED = (300.0, 100.0, 400.0, 220.0)


def test_the_first_frame_is_counted_then_every_period() -> None:
    switch = MultiFaceSwitch(check_period_s=1.0)
    assert switch.check_due(0.0)
    switch.counted(0.0, 1)
    assert not switch.jumped(0.0, BOX)  # counted on this very frame
    due = [t for t in np.arange(0.1, 3.05, 0.1) if switch.check_due(t) and not switch.counted(t, 1)]
    assert due == pytest.approx([1.0, 2.0, 3.0], abs=0.051)
    assert switch.mode is FaceMode.SINGLE


def test_a_jump_or_a_face_coming_back_asks_for_a_count() -> None:
    switch = MultiFaceSwitch(check_period_s=10.0)
    switch.counted(0.0, 1)
    switch.jumped(0.0, BOX)
    assert not switch.jumped(0.1, BOX)
    assert switch.jumped(0.2, MOVED)  # another place: may be another person
    assert not switch.jumped(0.3, None)
    assert switch.jumped(0.4, MOVED)  # back after a frame without a face


def test_two_faces_switch_to_multi_and_one_face_for_a_while_switches_back() -> None:
    switch = MultiFaceSwitch(check_period_s=1.0)
    switch.counted(0.0, 2)
    assert switch.mode is FaceMode.MULTI and not switch.check_due(5.0)
    switch.seen(0.1, 2, BOX)
    switch.seen(0.2, 1, BOX)
    switch.seen(0.5, 2, BOX)  # a second face again: the wait starts over
    switch.seen(0.6, 1, BOX)
    switch.seen(0.6 + MULTI_FACE_RETURN_S - 0.01, 1, BOX)
    assert switch.mode is FaceMode.MULTI
    switch.seen(0.6 + MULTI_FACE_RETURN_S, 1, BOX)
    assert switch.mode is FaceMode.SINGLE
    assert not switch.check_due(0.6 + MULTI_FACE_RETURN_S + 0.5)
    # The one-face landmarker finds the same driver: no count needed.
    assert not switch.jumped(1.7, BOX)


def test_a_bundle_without_a_detector_gives_none(tmp_path: Path) -> None:
    (tmp_path / "not-a-zip.task").write_bytes(b"nothing")
    assert detector_model_bytes(tmp_path / "not-a-zip.task") is None
    assert detector_model_bytes(tmp_path / "missing.task") is None


# ---------------------------------------------------------------- the real MediaPipe model


@pytest.fixture(scope="module")
def model_path() -> Path:
    return resolve_model(load_config(environ={}).model)


def scene(second_face: bool) -> npt.NDArray[np.uint8]:
    """The astronaut's face on the left; with `second_face` a smaller copy on the right."""
    face = cv2.cvtColor(skimage_data.astronaut()[20:260, 120:340], cv2.COLOR_RGB2BGR)
    canvas = np.full((260, 420, 3), 255, np.uint8)
    canvas[10:250, 0:220] = face
    if second_face:
        canvas[40:220, 240:405] = cv2.resize(face, (165, 180))
    return canvas


def test_a_second_face_is_found_within_the_check_period_and_dropped_after(
    model_path: Path,
) -> None:
    fps = 10.0
    # 2 s one face, 3 s two faces, 3 s one face again.
    plan = [False] * 20 + [True] * 30 + [False] * 30
    images = {False: scene(False), True: scene(True)}
    config = LandmarksConfig(multi_face_check_s=1.0)
    faces, modes = [], []
    with MediaPipeLandmarker(config, model_path, video=True) as detector:
        counter = detector._counter
        assert counter is not None
        counts = []
        original = counter.count

        def counting(image: object) -> int:
            counts.append(1)
            return original(image)

        counter.count = counting  # type: ignore[method-assign]
        for index, two in enumerate(plan):
            detection = detector.detect(images[two], index / fps)
            faces.append(len(detection.faces))
            modes.append(detector.face_mode)
            driver = detection.driver
            assert driver is not None and driver.box_px[2] < 230  # always the left, larger face
    assert modes[:20] == [FaceMode.SINGLE] * 20 and faces[:20] == [1] * 20
    first_two = faces.index(2)
    assert 20 <= first_two <= 20 + int(fps * 1.0)  # seen within one check period
    assert all(count == 2 for count in faces[first_two:50])
    assert modes[55] is FaceMode.MULTI  # the second face has just gone
    back = modes.index(FaceMode.SINGLE, first_two)
    assert back - 50 == pytest.approx(MULTI_FACE_RETURN_S * fps, abs=2)
    assert modes[-1] is FaceMode.SINGLE and faces[-1] == 1
    # Counting stayed rare: about once a second while one face was tracked.
    assert len(counts) <= 2 + 8 + 2


def test_check_period_zero_always_runs_the_multi_face_landmarker(model_path: Path) -> None:
    config = LandmarksConfig(multi_face_check_s=0.0)
    with MediaPipeLandmarker(config, model_path, video=True) as detector:
        assert detector._counter is None and detector._single_landmarker is None
        detection = detector.detect(scene(True), 0.0)
        assert len(detection.faces) == 2 and detector.face_mode is FaceMode.MULTI


def test_a_face_that_moves_away_from_the_tracked_place_is_found_on_the_same_frame(
    model_path: Path,
) -> None:
    """The one-face landmarker looks for the face where it was; when it is gone from there,
    the same frame is searched again (as the multi-face landmarker's every-frame detector did)."""
    face = cv2.cvtColor(skimage_data.astronaut()[20:260, 120:340], cv2.COLOR_RGB2BGR)
    left = np.full((260, 700, 3), 255, np.uint8)
    left[10:250, 0:220] = face
    right = np.full((260, 700, 3), 255, np.uint8)
    right[10:250, 470:690] = face
    with MediaPipeLandmarker(LandmarksConfig(), model_path, video=True) as detector:
        for index in range(5):
            assert detector.detect(left, index / 10).driver is not None
        moved = detector.detect(right, 0.5).driver
        assert detector.face_mode is FaceMode.SINGLE
    assert moved is not None and moved.box_px[0] > 400


def test_a_count_on_a_jump_waits_for_the_periodic_count_of_the_same_frame(
    model_path: Path,
) -> None:
    """The periodic count runs on its own thread; a jump on the same frame asks for a count at
    once. Both use one detector (its input buffer, LiteRT's interpreter), which must never run
    twice at a time: LiteRT refused with "at least 1 reference to internal data" and the run
    ended (a replay under load). The counts now follow each other on the counting thread."""
    import threading
    import time

    face = cv2.cvtColor(skimage_data.astronaut()[20:260, 120:340], cv2.COLOR_RGB2BGR)
    left = np.full((260, 700, 3), 255, np.uint8)
    left[10:250, 0:220] = face
    right = np.full((260, 700, 3), 255, np.uint8)
    right[10:250, 470:690] = face
    overlaps, counts = [], []
    busy = threading.Lock()

    class OneAtATime:
        """The detector, slowed down, noting a second count that starts while one runs."""

        def __init__(self, counter: Any) -> None:
            self.counter = counter

        def count(self, image: Any) -> int:
            if not busy.acquire(blocking=False):
                overlaps.append(threading.current_thread().name)
                return int(self.counter.count(image))
            try:
                time.sleep(0.3)
                counts.append(threading.current_thread().name)
                return int(self.counter.count(image))
            finally:
                busy.release()

        def close(self) -> None:
            self.counter.close()

    config = LandmarksConfig(multi_face_check_s=0.5)
    with MediaPipeLandmarker(config, model_path, video=True) as detector:
        slow = OneAtATime(detector._counter)
        detector._background.close()  # type: ignore[union-attr]
        detector._counter = slow  # type: ignore[assignment]
        detector._background = BackgroundCount(slow)
        for index in range(5):
            assert detector.detect(left, index / 10).driver is not None
        moved = detector.detect(right, 0.5).driver  # the periodic count is due: and a jump
    assert moved is not None and moved.box_px[0] > 400
    assert overlaps == [] and len(counts) >= 3


def test_a_periodic_count_is_taken_at_the_next_frame_even_when_it_is_slow() -> None:
    """A replay gives the same results every time: a count started on one frame always takes
    effect on the next, on whichever thread and however late it finishes."""
    import threading
    import time

    threads: list[str] = []

    class SlowCounter:
        def count(self, image: object) -> int:
            time.sleep(0.05)
            threads.append(threading.current_thread().name)
            return 2

    background = BackgroundCount(SlowCounter())  # type: ignore[arg-type]
    try:
        assert background.take() is None
        background.start(1.0, "frame 10")
        background.start(1.1, "frame 11")  # one count at a time: ignored
        assert background.pending
        assert background.take() == (1.0, 2)
        assert not background.pending and background.take() is None
    finally:
        background.close()
    assert len(threads) == 1 and threads[0].startswith("roadgaze-facecount")


def pair() -> npt.NDArray[np.uint8]:
    """Two people side by side: the astronaut on the image's left, a copy 0.85 times her size
    on the right."""
    face = cv2.cvtColor(skimage_data.astronaut()[20:260, 120:340], cv2.COLOR_RGB2BGR)
    canvas = np.full((260, 460, 3), 255, np.uint8)
    canvas[10:250, 0:220] = face
    canvas[28:232, 250:437] = cv2.resize(face, (187, 204))
    return canvas


@pytest.mark.parametrize(("cabin", "right"), [("lhd", True), ("rhd", False)])
def test_the_driver_is_the_face_in_the_drivers_seat_not_the_largest(
    model_path: Path, cabin: str, right: bool
) -> None:
    """Left-hand drive, camera in front: the driver is on the image's right although the face on
    the left is larger (the "largest" rule took the left one); right-hand drive: the left."""
    config = Config(monitor=MonitorConfig(cabin=cabin))  # type: ignore[arg-type]
    image = pair()
    with MediaPipeLandmarker.from_config(config, video=True) as detector:
        chosen = [detector.detect(image, index / 10).driver for index in range(10)]
    with MediaPipeLandmarker.from_config(config) as still:
        detection = still.detect(image)
    assert len(detection.faces) == 2 and detection.driver_ambiguous == ""
    for driver in [*chosen, detection.driver]:
        assert driver is not None and (driver.box_px[0] > 230) is right


def test_a_recordings_driver_is_found_even_where_one_face_is_tracked(model_path: Path) -> None:
    """One face for 0.5 s (the one-face landmarker tracks it), then a second appears beside it:
    with a recording that chose the newcomer, that very frame is counted again and its driver
    is the newcomer, although the periodic count is 10 s away."""
    config = LandmarksConfig(multi_face_check_s=10.0)
    one, two = scene(False), pair()
    with MediaPipeLandmarker(config, model_path) as still:
        newcomer = max(still.detect(two).faces, key=lambda face: face.box_px[0]).box_px
    with MediaPipeLandmarker(config, model_path, video=True) as detector:
        for index in range(5):
            assert detector.detect(one, index / 10).driver is not None
        detector.follow(RecordedDriver(newcomer))
        followed = detector.detect(two, 0.5)
        mode = detector.face_mode
        detector.follow(None)
        held = detector.detect(two, 0.6)
    assert mode is FaceMode.MULTI and len(followed.faces) == 2
    for detection in (followed, held):
        assert detection.driver is not None and detection.driver.box_px[0] > 230
