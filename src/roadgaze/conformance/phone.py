"""The scenarios of advanced phone use (Euro NCAP 2026, the dossier's phone rows): the driver
looks at the road at 70 km/h, then holds a phone up in the outer hand for `HOLD_S`, the head
still on the road and the eyes on the phone (the sheet's "lizard"), then puts it down. The
service must warn (`phone_use`) within the rule's time of the phone coming up, and heighten
forward and lane support by then (earlier is as good: the eyes on the phone may already be off
the road).

The phone is held at the wheel (9-11 o'clock in a left-hand-drive cabin, 1-3 in a right-hand-
drive one), higher, beside the face in view of the windscreen, or low over the wheel's centre in
view of the instrument cluster (`roadgaze.synth.phone_hand`), seen through a wider lens
(`PHONE_ZOOM`) so the hand at the wheel is in the picture.
"""

from __future__ import annotations

from dataclasses import replace

from roadgaze.config import MonitorConfig
from roadgaze.conformance import expect
from roadgaze.conformance.matrix import FAST_KMH, ahead, back
from roadgaze.conformance.model import Scenario, Segment
from roadgaze.conformance.support import support_requirements
from roadgaze.monitor.protocols import euroncap

HOLD_S = 4.0
"""How long the phone is held up: past the rule's 3 s."""
PHONE_ZOOM = 0.7
"""The lens of the phone scenarios (a face 0.7 times as wide): the wheel in view."""
DETECT_LATENCY_S = 0.6
"""How much later than the rule's time the warning may come beyond the timer's own margin: the
palm detector looks for a new hand at most every `[hands] detect_interval_s` (0.6 s)."""
KINDS = ("phone_use",)
PLACES = {
    "wheel": ("a phone held up at the wheel", (15.0, -20.0)),
    "windscreen": ("a phone held up in view of the windscreen", (12.0, -8.0)),
    "cluster": ("a phone held up in view of the instrument cluster", (4.0, -18.0)),
}
"""Each place the phone is held (`roadgaze.synth.phone_hand.PLACES`), what it is and the eyes'
look at it, the head still (the sheet's "lizard"): eye-in-head yaw toward the outer hand and
pitch, degrees (roadgaze's estimate of where the phone is)."""


def phone_name(place: str) -> str:
    """The scenario of the phone held at `place` (`phone_wheel_70`)."""
    return f"phone_{place}_70"


def phone_scenarios(config: MonitorConfig) -> list[Scenario]:
    """A phone held up `HOLD_S` at each of `PLACES` at 70 km/h: `phone_use` within the rule's
    time, support heightened by then until the phone is put down."""
    scenarios = []
    outer = 1.0 if config.cabin == "lhd" else -1.0
    for place, (what, (eye_yaw_deg, eye_pitch_deg)) in PLACES.items():
        name = phone_name(place)
        text = f"{what} {HOLD_S:g} s at {FAST_KMH:g} km/h: phone_use warning"
        warns = expect.timer(config, euroncap.PHONE_USE, KINDS, f"{name}.warns", text, "phone")
        early_s, late_s = warns.window_s or (0.0, 0.0)
        warns = replace(warns, window_s=(early_s, late_s + DETECT_LATENCY_S))
        support = tuple(
            replace(
                requirement,
                text=f"{requirement.text.partition(' within')[0]} by the warning at the "
                "latest, held until the phone is put down",
                window_s=(0.0, late_s + DETECT_LATENCY_S),
                applies=warns.applies,
            )
            for requirement in support_requirements(config, name, "phone", "back")
        )
        held = Segment(
            HOLD_S, eye_yaw_deg=outer * eye_yaw_deg, eye_pitch_deg=eye_pitch_deg, label="phone"
        )
        segments = (ahead(), held, back())
        scenarios.append(
            Scenario(
                name,
                text,
                segments,
                FAST_KMH,
                (warns, *support),
                conditions=(f"phone_{place}",),
                worn_from="phone",
                worn_until="back",
                zoom=PHONE_ZOOM,
            )
        )
    return scenarios
