"""The rules of forward and lane support: when the service asks the vehicle's forward-collision
warning (forward) and lane keeping (lane) to be heightened. Pure.

One set per channel (`forward`, `lane`), so each output names its own rule; both channels read
the same settings (`support_raise_s`, `support_clear_s`, `support_hold_impaired`).
"""

from __future__ import annotations

from dataclasses import dataclass

from roadgaze.monitor.events import Rule

__all__ = ["CHANNELS", "FORWARD", "LANE", "RULES", "SupportRules", "support_rules"]

FORWARD, LANE = "forward", "lane"
CHANNELS = (FORWARD, LANE)

_SHEET = (
    "Euro NCAP 2026 Safe Driving, driver monitoring (the rating calculator's sheet 'DE - DM "
    "pred.'): forward and lane support on every glance row, driving-task glances (mirrors, "
    "cluster) included, with no warning for those"
)
_FATIGUE = (
    "Euro NCAP driver state monitoring, fatigue: forward-collision and lane departure warning "
    "sensitivity raised after any fatigue state until the next ignition cycle (Optalert's "
    "summary of the protocol, optalert.com/euro-ncap-warnings-and-interventions)"
)


@dataclass(frozen=True, slots=True)
class SupportRules:
    """The rules one support channel applies."""

    off_road: Rule
    """The gaze off the forward road (any other zone, the eyes closed): heightened."""
    unknown: Rule
    """The service cannot tell (no face, two faces, eyes unavailable, no speed, a bad
    frame): heightened (fail-safe)."""
    clear: Rule
    """Normal again after watching the road this long with everything known."""
    impaired: Rule
    """An impairment alert: heightened to the end of the trip."""

    @property
    def all(self) -> tuple[Rule, ...]:
        return (self.off_road, self.unknown, self.clear, self.impaired)


def support_rules(channel: str) -> SupportRules:
    """The rules of `channel` (`forward` or `lane`)."""
    return SupportRules(
        off_road=Rule(
            f"euroncap.support.{channel}",
            "support_raise_s",
            "s",
            f"{_SHEET}; the 0.5 s bound on this setting is roadgaze's (the protocol's own time "
            "was not read here)",
            "the gaze off the forward road this long: support heightened",
        ),
        unknown=Rule(
            f"roadgaze.support.{channel}.unknown",
            "support_raise_s",
            "s",
            "roadgaze's choice (fail-safe: where the driver looks is not known)",
            "no face, two faces, eyes unavailable, no speed or a bad frame this long: "
            "support heightened",
        ),
        clear=Rule(
            f"roadgaze.support.{channel}.clear",
            "support_clear_s",
            "s",
            "roadgaze's choice (Euro NCAP's VATS re-arm time, 2 s on the road; no support "
            "clearing time of the protocol was read here)",
            "support normal again after watching the road this long, everything known",
        ),
        impaired=Rule(
            f"euroncap.support.{channel}.impaired",
            "support_hold_impaired",
            "on/off",
            _FATIGUE,
            "an impairment alert (drowsy, microsleep, sleep) holds support to the end of the trip",
        ),
    )


RULES: tuple[Rule, ...] = tuple(rule for c in CHANNELS for rule in support_rules(c).all)
