"""The scenarios of timed rules: VATS, the eyes (microsleep, sleep, unresponsive, an eyes-only
glance) and the camera (a covered lens, frozen frames, no face); the rest and the conventions of
every scenario: `roadgaze.conformance.matrix`."""

from __future__ import annotations

from roadgaze.config import MonitorConfig
from roadgaze.conformance import expect
from roadgaze.conformance.matrix import (
    BEYOND_AREA_DEG,
    EYES_LAP_DEG,
    FAST_KMH,
    LONG_LOOK_S,
    LOOK_S,
    VATS_GLANCE_S,
    VATS_ROAD_S,
    ahead,
    back,
    look,
    zone_target,
)
from roadgaze.conformance.model import Requirement, Scenario, Segment
from roadgaze.monitor.protocols import addw, euroncap
from roadgaze.monitor.protocols import roadgaze as own_rules


def vats_scenarios(config: MonitorConfig) -> list[Scenario]:
    """Glances at the centre stack, each below the trigger: 10 s within 30 s warns, 8.8 s not."""
    target = zone_target(config, "centre_stack")
    threshold_s = euroncap.VATS.value(config) or 0.0
    count = int(threshold_s // VATS_GLANCE_S) + 1
    glances: list[Segment] = []
    for index in range(count):
        glances.append(look(target, VATS_GLANCE_S, "look" if index == 0 else f"glance{index}"))
        glances.append(Segment(VATS_ROAD_S))
    # The off-road time reaches the threshold in the last glance: when the rendered head's time
    # beyond the road's edge adds up to it (expect.vats).
    warns = expect.vats(
        config,
        "vats_70.warns",
        f"{count} glances of {VATS_GLANCE_S:g} s at the centre stack at 70 km/h",
        (ahead(), *glances, back()),
        (count - 1) * VATS_ROAD_S,
    )
    text = f"{count - 1} glances of {VATS_GLANCE_S:g} s within {config.vats_window_s:g} s: no VATS"
    quiet = Requirement(
        "vats_below_70.quiet",
        text,
        expect.source_of(euroncap.VATS),
        ("vats",),
        None,
        applies=expect.applies(config, euroncap.VATS),
    )
    short = expect.no_distraction(
        config, FAST_KMH, "vats_70.no_long", "each glance below the trigger: no long distraction"
    )
    return [
        Scenario("vats_70", warns.text, (ahead(), *glances, back()), FAST_KMH, (warns, short)),
        Scenario("vats_below_70", text, (ahead(), *glances[:-2], back()), FAST_KMH, (quiet,)),
    ]


def eye_scenarios(config: MonitorConfig) -> list[Scenario]:
    """Eyes-only glance, microsleep, sleep, unresponsive (eyes closed; head away)."""

    def closed(duration_s: float) -> Segment:
        return Segment(duration_s, openness=0.0, label="event")

    microsleep = expect.timer(
        config,
        euroncap.MICROSLEEP,
        ("microsleep",),
        "microsleep_70.warns",
        "eyes closed 1.5 s at 70 km/h",
    )
    no_sleep = Requirement(
        "microsleep_70.no_sleep",
        "a 1.5 s closure is no sleep",
        expect.source_of(euroncap.SLEEP),
        ("sleep",),
        None,
        "event",
        expect.applies(config, euroncap.SLEEP),
    )
    sleep = expect.timer(
        config, euroncap.SLEEP, ("sleep",), "sleep_70.warns", "eyes closed 4 s at 70 km/h"
    )
    unresponsive = expect.timer(
        config,
        euroncap.UNRESPONSIVE_CLOSED,
        ("unresponsive",),
        "unresponsive_closed_70.warns",
        "eyes closed 7 s at 70 km/h",
    )
    far = -(config.distraction_yaw_deg + BEYOND_AREA_DEG)
    trigger = expect.trigger_at(config, FAST_KMH)
    away = expect.timer(
        config,
        euroncap.UNRESPONSIVE_AFTER_WARNING,
        ("unresponsive",),
        "unresponsive_away_70.warns",
        "8 s look to the right side window at 70 km/h",
        "look",
        trigger.warn_s if trigger else 0.0,
    )
    eyes_only = expect.distraction(
        config, FAST_KMH, "eyes_only_lap_70.warns", "4 s eyes-only glance into the lap, head still"
    )
    eyes_down = Segment(
        LOOK_S, eye_yaw_deg=EYES_LAP_DEG[0], eye_pitch_deg=EYES_LAP_DEG[1], label="look"
    )
    return [
        Scenario(
            "eyes_only_lap_70", eyes_only.text, (ahead(), eyes_down, back()), FAST_KMH, (eyes_only,)
        ),
        Scenario(
            "microsleep_70",
            microsleep.text,
            (ahead(), closed(1.5), back()),
            FAST_KMH,
            (microsleep, no_sleep),
            fast=True,
        ),
        Scenario("sleep_70", sleep.text, (ahead(), closed(4.0), back()), FAST_KMH, (sleep,)),
        Scenario(
            "unresponsive_closed_70",
            unresponsive.text,
            (ahead(), closed(7.0), back()),
            FAST_KMH,
            (unresponsive,),
        ),
        Scenario(
            "unresponsive_away_70",
            away.text,
            (ahead(), look((far, 0.0), LONG_LOOK_S), back()),
            FAST_KMH,
            (away,),
        ),
    ]


def camera_scenarios(config: MonitorConfig) -> list[Scenario]:
    """A covered lens, frozen frames, the driver out of view."""
    failure = ("temporary_failure",)
    covered = expect.timer(
        config,
        addw.FAILURE_TEMPORARY,
        failure,
        "covered_70.fails",
        "lens covered 5 s at 70 km/h: temporary failure",
    )
    frozen = expect.timer(
        config,
        own_rules.FROZEN,
        failure,
        "frozen_70.fails",
        "frames frozen 13 s at 70 km/h: temporary failure",
    )
    gone = expect.timer(
        config,
        own_rules.UNAVAILABLE,
        ("driver_unavailable",),
        "no_face_70.unavailable",
        "no face 13 s at 70 km/h: driver unavailable",
    )
    gone_failure = expect.timer(
        config,
        own_rules.NO_FACE,
        failure,
        "no_face_70.fails",
        "no face 13 s at 70 km/h: temporary failure",
    )
    return [
        Scenario(
            "covered_70",
            covered.text,
            (ahead(), Segment(5.0, camera="covered", label="event"), back()),
            FAST_KMH,
            (covered,),
            fast=True,
        ),
        Scenario(
            "frozen_70",
            frozen.text,
            (ahead(), Segment(13.0, camera="frozen", label="event"), back()),
            FAST_KMH,
            (frozen,),
        ),
        Scenario(
            "no_face_70",
            gone.text,
            (ahead(), Segment(13.0, camera="no_face", label="event"), back()),
            FAST_KMH,
            (gone, gone_failure),
        ),
    ]
