"""The `phone_use` behaviour through the monitor: a phone judged in hand for `phone_use_s`
while moving warns once, gaps shorter than `phone_gap_s` are bridged, putting it down clears it,
and without phone detection nothing is raised."""

from __future__ import annotations

from collections.abc import Callable

from roadgaze.config import MonitorConfig
from roadgaze.monitor import Monitor
from roadgaze.types import AlertKind, AlertLevel, HandSide, PhoneJudgement, PhonePose, PoseSample

FPS = 15
IN_HAND = PhoneJudgement(phone_use=True, score=0.9, hand=HandSide.RIGHT, pose=PhonePose.HELD_UP)
NO_PHONE = PhoneJudgement(phone_use=False, score=0.1)
UNJUDGED = PhoneJudgement(phone_use=None, score=None)


def drive(
    phone_at: Callable[[float], PhoneJudgement | None],
    seconds: float,
    speed_kmh: float | Callable[[float], float] = 70.0,
    protocol: str = "euroncap",
) -> list[tuple[float, AlertKind, AlertLevel, tuple[AlertKind, ...], str]]:
    """The alerts of a drive looking at the road, the phone judged by `phone_at(t_s)`."""
    monitor = Monitor(MonitorConfig(protocol=protocol))
    seen = []
    for frame in range(round(seconds * FPS)):
        t_s = frame / FPS
        sample = PoseSample(
            t_s=t_s,
            frame=frame,
            face=True,
            yaw_raw_deg=0.0,
            yaw_deg=0.0,
            yaw_rate_dps=0.0,
            yaw_std_deg=1.0,
            phone=phone_at(t_s),
        )
        speed = speed_kmh(t_s) if callable(speed_kmh) else speed_kmh
        for alert in monitor.update(sample, speed_kmh=speed):
            seen.append((round(t_s, 2), alert.kind, alert.level, alert.clears, alert.reason))
    return seen


def test_a_phone_held_up_for_4_s_at_70_kmh_warns_3_s_in_and_clears_when_put_down() -> None:
    seen = drive(lambda t: IN_HAND if 1.0 <= t < 5.0 else NO_PHONE, 8.0)
    assert [(t, kind, level) for t, kind, level, _, _ in seen] == [
        (4.0, AlertKind.PHONE_USE, AlertLevel.WARNING),
        (5.67, AlertKind.CLEARED, AlertLevel.INFO),  # 0.7 s without the phone (phone_gap_s)
    ]
    assert seen[0][4] == "phone held_up, right hand for 3.0 s"
    assert seen[1][3] == (AlertKind.PHONE_USE,)


def test_a_judgement_that_drops_out_briefly_does_not_restart_the_time() -> None:
    # In hand from 1 s, missed (cannot judge, then no phone) for 0.5 s at 2.0 and 3.0 s.
    def phone_at(t: float) -> PhoneJudgement:
        if 2.0 <= t < 2.5:
            return UNJUDGED
        if 3.0 <= t < 3.5:
            return NO_PHONE
        return IN_HAND if t >= 1.0 else NO_PHONE

    assert [(t, kind) for t, kind, *_ in drive(phone_at, 6.0)] == [(4.0, AlertKind.PHONE_USE)]


def test_a_gap_of_phone_gap_s_restarts_the_time() -> None:
    seen = drive(lambda t: IN_HAND if 1.0 <= t < 2.5 or t >= 3.2 else NO_PHONE, 7.0)
    assert [(t, kind) for t, kind, *_ in seen] == [(6.2, AlertKind.PHONE_USE)]


def test_no_warning_while_stopped_or_under_addw_alone_or_without_phone_detection() -> None:
    assert drive(lambda t: IN_HAND, 8.0, speed_kmh=10.0) == []
    assert drive(lambda t: IN_HAND, 8.0, protocol="addw") == []
    assert drive(lambda t: None, 8.0) == []  # phone detection off: nothing forged
    assert [kind for _, kind, *_ in drive(lambda t: IN_HAND, 8.0, protocol="both")] == [
        AlertKind.PHONE_USE
    ]


def test_stopping_the_car_clears_a_phone_use_warning() -> None:
    seen = drive(lambda t: IN_HAND, 6.0, speed_kmh=lambda t: 70.0 if t < 5.0 else 0.0)
    assert [(t, kind) for t, kind, *_ in seen] == [
        (3.0, AlertKind.PHONE_USE),
        (5.0, AlertKind.CLEARED),
    ]
