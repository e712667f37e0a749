"""The scenarios of the non-functional notices (Euro NCAP 2026, DSM general requirements): the
driver looks at the road at 70 km/h wearing what may hide the eyes (dark sunglasses, a cap, a
hat, a hair fringe, thick eyelash makeup) or gripping the top of the wheel in front of a camera on
the steering column, put on after `AHEAD_S` bare-faced and held `HOLD_S`; the service must say
`non_functional` within the protocol's 10 s of putting it on. The conditions the service must
keep working under (night, clear sunglasses, short and long facial hair, a face mask, talking)
must raise no notice at all (rendered from the first frame: night and talking cannot be put
on).

A notice scenario that FAILs because the service still judges the eyes is not a fault in itself:
the dossier asks for the notice only where the condition is not shown functional
(`roadgaze.conformance.dossier`)."""

from __future__ import annotations

from roadgaze.config import MonitorConfig
from roadgaze.config.notices import NOTICE_LIMIT_S
from roadgaze.conformance import expect
from roadgaze.conformance.matrix import FAST_KMH, ahead, back
from roadgaze.conformance.model import Requirement, Scenario, Segment
from roadgaze.monitor.protocols import euroncap

HOLD_S = 12.0
"""How long the condition is held, looking at the road: past the protocol's 10 s."""
KINDS = ("non_functional",)
NOTICES: dict[str, tuple[str, str]] = {
    "dark_sunglasses": ("dark sunglasses", "front"),
    "cap": ("a cap", "front"),
    "hat": ("a hat", "front"),
    "fringe": ("a hair fringe over the eyes", "front"),
    "eyelash_makeup": ("thick eyelash makeup", "front"),
    "hand_at_12": ("a hand at the top of the wheel (camera on the column)", "steering_column"),
}
"""Each condition that may hide the driver: what it is, and the camera mounting it is seen from
(the hand obstructs a camera behind the wheel; from the front it stays below the face)."""
QUIET = ("night", "clear_sunglasses", "stubble", "beard", "mask", "talking")
"""The conditions the service must keep working under: no notice."""


def notice_key(condition: str) -> str:
    """The requirement key of the notice under `condition` (`notice_cap_70.told`)."""
    return f"notice_{condition}_70.told"


def quiet_key(condition: str) -> str:
    return f"notice_quiet_{condition}_70.quiet"


def _worn() -> Segment:
    return Segment(HOLD_S, label="worn")


def notice_scenarios(config: MonitorConfig) -> list[Scenario]:
    """A notice within 10 s for each condition of `NOTICES`; none for those of `QUIET`."""
    source = expect.source_of(euroncap.NON_FUNCTIONAL)
    applies = expect.applies(config, euroncap.NON_FUNCTIONAL)
    earliest_s = max(0.0, euroncap.NON_FUNCTIONAL.limit(config) - expect.TIMER_EARLY_S)
    scenarios = []
    for condition, (what, mounting) in NOTICES.items():
        text = f"{what}, looking at the road {HOLD_S:g} s at 70 km/h: notice within 10 s"
        told = Requirement(
            notice_key(condition),
            text,
            source,
            KINDS,
            (earliest_s, NOTICE_LIMIT_S),
            "worn",
            applies,
        )
        name = notice_key(condition).partition(".")[0]
        scenarios.append(
            Scenario(
                name,
                text,
                (ahead(), _worn(), back()),
                FAST_KMH,
                (told,),
                mounting=mounting,
                conditions=(condition,),
                worn_from="worn",
            )
        )
    for condition in QUIET:
        text = f"{condition.replace('_', ' ')}, looking at the road {HOLD_S:g} s: no notice"
        quiet = Requirement(quiet_key(condition), text, source, KINDS, None, "worn", applies)
        name = quiet_key(condition).partition(".")[0]
        scenarios.append(
            Scenario(
                name, text, (ahead(), _worn(), back()), FAST_KMH, (quiet,), conditions=(condition,)
            )
        )
    return scenarios
