"""The drowsiness scenarios: a drowsy drive (slow long blinks, yawns, a nod) at 70 km/h must reach
the warning level and warn; the same drive at 40 km/h (below Euro NCAP's 50 km/h for impairment)
and an alert driver at 70 km/h (short blinks, no yawn, no nod) must not. The conventions of every
scenario: `roadgaze.conformance.matrix`."""

from __future__ import annotations

from roadgaze.config import MonitorConfig
from roadgaze.conformance import expect
from roadgaze.conformance.matrix import FAST_KMH, ahead, back
from roadgaze.conformance.model import Requirement, Scenario, Segment
from roadgaze.monitor.protocols import Rule, euroncap

__all__ = ["BELOW_KMH", "drowsiness_scenarios", "drowsy_segments"]

BELOW_KMH = 40.0
"""Below Euro NCAP's 50 km/h for impairment."""
CYCLE_S = 3.0
"""One blink every 3 s (20 a minute: within spontaneous blinking's 10-20 a minute at most)."""
LONG_BLINK_S = 0.7
"""A drowsy blink: the lids closed 0.7 s (a long blink is 0.5 s or more, `long_blink_s`)."""
SHORT_BLINK_S = 0.1
"""An alert blink: the lids closed 0.1 s (a spontaneous blink lasts 0.1-0.15 s)."""
YAWN_S = 3.5
"""A yawn's segment: the jaw eases open over 0.8 s, holds, and eases shut (a yawn lasts about
6 s, Provine 1986; shortened so a drive stays within 25 s, still longer than `yawn_min_s` above
`yawn_opening`)."""
YAWN_OPENING = 0.8
"""A yawn opens the jaw to 0.8 of the renderer's wide yawn (lips 4-5 cm apart)."""
NOD_PITCH_DEG = -25.0
"""A nod drops the head 25 deg below the road (eyes closed), then it comes back up."""
NOD_CLOSED_S, NOD_DOWN_S, NOD_UP_S = 0.2, 0.6, 1.0
"""A nod: the lids close, 0.2 s later the head drops (its 0.5 s eased turn) and holds 0.6 s,
then comes back up and the eyes open; the closure (about 0.8 s) is a long blink, not yet a
microsleep."""


def _blink(
    open_s: float, closed_s: float, label: str = "", mouth: float = 0.0
) -> tuple[Segment, ...]:
    return (
        Segment(open_s, label=label, mouth_open=mouth),
        Segment(closed_s, openness=0.0),
    )


def drowsy_segments() -> tuple[Segment, ...]:
    """About 17 s of drowsy driving: a long blink every 3 s (two after a yawn), one of them a
    nod (the head drops with the lids closed and comes back up)."""
    open_s = CYCLE_S - LONG_BLINK_S
    nod = (
        Segment(CYCLE_S - NOD_CLOSED_S - NOD_DOWN_S - NOD_UP_S),
        Segment(NOD_CLOSED_S, openness=0.0),
        Segment(NOD_DOWN_S, pitch_deg=NOD_PITCH_DEG, openness=0.0, label="nod"),
        Segment(NOD_UP_S),
    )
    return (
        *_blink(open_s, LONG_BLINK_S, "event"),
        *_blink(YAWN_S, LONG_BLINK_S, mouth=YAWN_OPENING),
        *nod,
        *_blink(open_s, LONG_BLINK_S),
        *_blink(YAWN_S, LONG_BLINK_S, mouth=YAWN_OPENING),
    )


def alert_segments() -> tuple[Segment, ...]:
    """As long as the drowsy part, awake: a short blink every 5 s, no yawn, no nod."""
    count = round(sum(s.duration_s for s in drowsy_segments()) / CYCLE_S)
    segments: list[Segment] = []
    for index in range(count):
        segments.extend(
            _blink(CYCLE_S - SHORT_BLINK_S, SHORT_BLINK_S, "event" if not index else "")
        )
    return tuple(segments)


def _no_drowsy(config: MonitorConfig, key: str, text: str, rule: Rule) -> Requirement:
    """No `drowsy` anywhere in the drive (by `rule`, when its protocol is configured)."""
    source = expect.source_of(rule)
    return Requirement(key, text, source, ("drowsy",), None, "event", expect.applies(config, rule))


def drowsiness_scenarios(config: MonitorConfig) -> list[Scenario]:
    """Drowsy at 70 km/h warns within the drowsy part; alert at 70 and drowsy at 40 do not."""
    drowsy = drowsy_segments()
    drowsy_s = sum(s.duration_s for s in drowsy)
    source = expect.source_of(euroncap.DROWSINESS)
    fast = f"{FAST_KMH:g} km/h"
    text = f"{drowsy_s:.1f} s of long blinks, two yawns and a nod at {fast}: drowsy"
    warns = Requirement(
        "drowsy_70.warns",
        text,
        source,
        ("drowsy",),
        (0.0, drowsy_s),
        "event",
        expect.applies(config, euroncap.DROWSINESS),
    )
    alert_text = f"an alert driver (short blinks) at {fast}: no drowsiness warning"
    slow_text = f"the drowsy drive at {BELOW_KMH:g} km/h (below 50): no drowsiness warning"
    alert = _no_drowsy(config, "alert_70.quiet", alert_text, euroncap.DROWSINESS)
    slow = _no_drowsy(config, "drowsy_40.quiet", slow_text, euroncap.DROWSINESS_SPEED)
    return [
        Scenario("drowsy_70", text, (ahead(), *drowsy, back()), FAST_KMH, (warns,)),
        Scenario("alert_70", alert_text, (ahead(), *alert_segments(), back()), FAST_KMH, (alert,)),
        Scenario("drowsy_40", slow_text, (ahead(), *drowsy, back()), BELOW_KMH, (slow,)),
    ]
