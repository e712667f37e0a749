"""The drowsiness level: its arithmetic on scripted eye, mouth and pitch tracks (each expectation
in closed form), the mouth's opening from the lips' landmarks, and the `drowsy` behaviour's speed
gate (50 km/h under Euro NCAP; an unknown speed warns and says so), and a nod through the whole
monitor."""

from __future__ import annotations

import numpy as np
import pytest

from fakes import eyes_of
from roadgaze.config import MonitorConfig
from roadgaze.monitor import Monitor
from roadgaze.monitor.behaviours import Drowsy, DrowsyState
from roadgaze.monitor.context import Context
from roadgaze.monitor.drowsiness import (
    BASE_LEVEL,
    DrowsinessSigns,
    level_of,
    mouth_opening,
    track_signs,
)
from roadgaze.monitor.episode import Episode
from roadgaze.monitor.events import Raise
from roadgaze.monitor.eyes import EyeMonitorState
from roadgaze.monitor.look import Look
from roadgaze.monitor.protocols import configured, euroncap, roadgaze
from roadgaze.monitor.zones import ZoneMap
from roadgaze.types import AlertKind, EyeStatus, EyesVerdict, FaceFeatures, PoseSample

CONFIG = MonitorConfig()
DT = 0.1


def eyes(
    perclos: float | None = None, blinks: tuple[float, ...] = (), judged_s: float = 0.0
) -> EyeMonitorState:
    """Eyes with PERCLOS, blinks of these durations (ending 1 s apart) and `judged_s` judged."""
    long_blinks = sum(1 for d in blinks if d >= CONFIG.long_blink_s)
    bins = tuple((i, 0.0, 1.0) for i in range(int(judged_s)))
    return EyeMonitorState(
        t_s=60.0,
        status=EyeStatus.OPEN,
        blinks=tuple((float(i), d) for i, d in enumerate(blinks)),
        bins=bins,
        verdict=EyesVerdict(perclos=perclos, blinks=len(blinks), long_blinks=long_blinks),
    )


def signs(yawns: int = 0, nods: int = 0) -> DrowsinessSigns:
    return DrowsinessSigns(yawns=tuple(range(yawns)), nods=tuple(range(nods)))


@pytest.mark.parametrize(
    ("state", "seen", "level"),
    [
        (eyes(), signs(), 5),
        (eyes(perclos=0.149), signs(), 5),
        (eyes(perclos=0.15), signs(), 7),  # PERCLOS alone: 5 + 2
        (eyes(blinks=(0.6, 0.6)), signs(), 5),  # two blinks: too few for either sign
        (eyes(blinks=(0.1, 0.1, 0.1)), signs(), 5),  # mean 0.10 s < 0.15 s
        (eyes(blinks=(0.1, 0.1, 0.25)), signs(), 6),  # mean 0.15 s: + 1
        (eyes(blinks=(0.6, 0.6, 0.6)), signs(), 5 + 2 + 1),  # long blinks + their duration
        (eyes(), signs(yawns=1), 5),
        (eyes(), signs(yawns=2), 6),  # yawns alone never warn
        (eyes(), signs(nods=1), 7),
        (eyes(blinks=(0.1, 0.1, 0.25)), signs(yawns=2), 7),  # two weak signs together
        (eyes(perclos=0.3, blinks=(0.6,) * 3), signs(yawns=3, nods=2), 9),  # capped at 9
    ],
)
def test_the_level_is_five_plus_the_points_of_the_signs_present(
    state: EyeMonitorState, seen: DrowsinessSigns, level: int
) -> None:
    assert level_of(CONFIG, state, seen).level == level


def test_the_blink_rate_is_a_sign_only_when_configured() -> None:
    # 30 blinks of 0.1 s in 60 s judged: 30 a minute.
    state = eyes(blinks=(0.1,) * 30, judged_s=60.0)
    assert level_of(CONFIG, state, signs()).level == BASE_LEVEL
    config = MonitorConfig(blink_rate_drowsy_per_min=30.0)
    found = level_of(config, state, signs())
    assert found.level == BASE_LEVEL + 1 and found.signs == ("30 blinks/min",)
    # Below the judged time PERCLOS needs, no rate is known.
    assert level_of(config, eyes(blinks=(0.1,) * 30, judged_s=20.0), signs()).level == 5


def run_mouth(track: list[tuple[float, float]], config: MonitorConfig = CONFIG) -> list[float]:
    """Yawn start times after (seconds, opening) segments sampled every DT."""
    seen, t = DrowsinessSigns(), 0.0
    for seconds, opening in track:
        for _ in range(round(seconds / DT)):
            seen = track_signs(config, seen, t, opening, 0.0, False)
            t = round(t + DT, 9)
    return list(seen.yawns)


def test_an_opening_held_two_seconds_is_one_yawn_speech_is_none() -> None:
    # Open at t = 1.0; counted once at 3.0 (held 2 s), not again while it stays open.
    assert run_mouth([(1.0, 0.0), (5.0, 0.8), (1.0, 0.0)]) == [1.0]
    assert run_mouth([(1.0, 0.0), (1.9, 0.8), (1.0, 0.0)]) == []  # 1.9 s: no yawn
    # Syllables: wide openings of 0.3 s, many of them, none a yawn.
    assert run_mouth([(0.3, 0.9), (0.2, 0.1)] * 40) == []
    # Below the opening, however long: no yawn.
    assert run_mouth([(10.0, 0.59)]) == []


def test_yawns_leave_the_window() -> None:
    track = [(1.0, 0.0), (3.0, 0.8), (70.0, 0.0)]
    assert run_mouth(track) == []  # started at 1 s, gone 60 s later
    assert run_mouth([*track[:2], (50.0, 0.0)]) == [1.0]


def run_pitch(track: list[tuple[float, float, bool]]) -> list[float]:
    """Nod times after (seconds, degrees below the road, eyes closed) segments every DT."""
    seen, t = DrowsinessSigns(), 0.0
    for seconds, below, closed in track:
        for _ in range(round(seconds / DT)):
            seen = track_signs(CONFIG, seen, t, None, below, closed)
            t = round(t + DT, 9)
    return list(seen.nods)


def test_a_short_drop_with_the_eyes_closed_is_a_nod() -> None:
    # Down at 1.0 s for 1.0 s, eyes closed: a nod counted when the head is back, at 2.0 s.
    assert run_pitch([(1.0, 0.0, False), (1.0, 20.0, True), (1.0, 0.0, False)]) == [2.0]
    # The same drop with the eyes open is a look down; one held 2.5 s is not a nod.
    assert run_pitch([(1.0, 0.0, False), (1.0, 20.0, False), (1.0, 0.0, False)]) == []
    assert run_pitch([(1.0, 0.0, True), (2.5, 20.0, True), (1.0, 0.0, False)]) == []
    # A drop of 14 deg is too small.
    assert run_pitch([(1.0, 0.0, False), (1.0, 14.0, True), (1.0, 0.0, False)]) == []


def face_with_mouth(gap_px: float, width_px: float, turned: float = 0.0) -> FaceFeatures:
    points = np.zeros((478, 3), np.float32)
    points[13] = (0.0, 0.0, 0.0)
    points[14] = (0.0, gap_px, 0.0)
    # A turned head foreshortens the width in x; the depth keeps it in 3-D.
    half = width_px / 2.0
    points[78] = (-half * np.cos(turned), 0.0, half * np.sin(turned))
    points[308] = (half * np.cos(turned), 0.0, -half * np.sin(turned))
    return FaceFeatures(0.0, 1.0, 0.5, 0.0, (0.0, 0.0, 1.0, 1.0), 1.0, points)


def test_the_mouths_opening_is_the_lip_gap_over_the_mouths_width_in_3d() -> None:
    assert mouth_opening(face_with_mouth(20.0, 40.0)) == pytest.approx(0.5)
    assert mouth_opening(face_with_mouth(20.0, 40.0, turned=0.7)) == pytest.approx(0.5)
    assert mouth_opening(None) is None
    few = FaceFeatures(0.0, 1.0, 0.5, 0.0, (0.0, 0.0, 1.0, 1.0), 1.0, np.zeros((3, 3)))
    assert mouth_opening(few) is None


DROWSY = Drowsy(roadgaze.DROWSY, euroncap.DROWSINESS, euroncap.DROWSINESS_SPEED)


def step(speed_kmh: float | None, protocol: str = "euroncap", moving: bool = True) -> list[Raise]:
    """The behaviour at one sample with the eyes at PERCLOS 0.2 (level 7)."""
    config = MonitorConfig(protocol=protocol)  # type: ignore[arg-type]
    sample = PoseSample(60.0, 900, True, 0.0, 0.0, None, None)
    context = Context(
        config=config,
        zones=ZoneMap(),
        protocols=configured(protocol),
        sample=sample,
        speed_kmh=speed_kmh,
        moving=moving,
        look=Look(),
        eyes=eyes(perclos=0.2),
        episode=Episode(),
        episode_ended=False,
        frame_issue="",
        trigger=None,
        active=(),
    )
    _, events = DROWSY.step(context, DrowsyState())
    return [e for e in events if isinstance(e, Raise)]


def test_under_euroncap_drowsiness_warns_from_50_kmh_and_at_unknown_speed() -> None:
    assert step(49.9) == []
    (at_50,) = step(50.0)
    assert at_50.kind is AlertKind.DROWSY and at_50.rule.key == "euroncap.drowsiness"
    assert at_50.reason == "drowsiness level 7: PERCLOS 0.20"
    (unknown,) = step(None)
    assert unknown.reason.endswith("; speed unknown")
    assert step(None, moving=False) == []  # standing still: never
    # Under ADDW alone, whenever moving (ADDW's lowest speed decides).
    assert len(step(30.0, protocol="addw")) == 1
    assert euroncap.DROWSINESS.impairment and not euroncap.DROWSINESS_SPEED.impairment


def nod_drive(speed_kmh: float | None) -> list[tuple[str, float, str]]:
    """The whole monitor: 3 s ahead, the lids close, 0.2 s later the head drops 20 deg for
    0.6 s, back up and open at 3.8 s (a 0.8 s closure: a long blink, no microsleep)."""
    config = MonitorConfig(protocol="euroncap", neutral_yaw_deg=0.0, neutral_pitch_deg=0.0)
    monitor, alerts = Monitor(config), []
    for frame in range(round(6.0 * 15)):
        t_s = frame / 15
        closed = 3.0 <= t_s + 1e-9 < 3.8
        pitch = -20.0 if 3.2 <= t_s + 1e-9 < 3.8 else 0.0
        sample = PoseSample(
            t_s, frame, True, 0.0, 0.0, 0.0, 1.0, n_faces=1, pitch_raw_deg=pitch,
            pitch_deg=pitch, eyes=eyes_of(openness=0.08) if closed else eyes_of(),
        )  # fmt: skip
        alerts += [(a.label, a.t_s, a.reason) for a in monitor.update(sample, speed_kmh)]
    return alerts


def test_a_nod_alone_reaches_level_7_through_the_whole_monitor_at_70_not_at_40() -> None:
    ((label, t_s, reason),) = nod_drive(70.0)
    assert label == "drowsy:warning" and reason == "drowsiness level 7: 1 nod"
    assert t_s == pytest.approx(3.8, abs=1 / 15 + 1e-6)  # when the head is back up
    assert nod_drive(40.0) == []
