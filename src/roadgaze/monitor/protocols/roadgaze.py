"""roadgaze's own rules beside the protocols: escalation, clearing, failure checks. Pure."""

from __future__ import annotations

from roadgaze.monitor.events import Rule

__all__ = [
    "CLEAR",
    "CRITICAL",
    "DROWSY",
    "FROZEN",
    "NO_FACE",
    "RULES",
    "UNAVAILABLE",
]

CRITICAL = Rule(
    "roadgaze.escalation.critical",
    "critical_after_warning_s",
    "s",
    "roadgaze's choice after openpilot's driver monitoring policy (warning, then a stronger "
    "alert a few seconds later)",
    "a distraction warning becomes critical this long after it (not before critical_distraction_s)",
)
CLEAR = Rule(
    "roadgaze.clear",
    "clear_on_road_s",
    "s",
    "roadgaze's choice",
    "distraction alerts clear after this long looking at the road",
)
UNAVAILABLE = Rule(
    "roadgaze.unavailable",
    "unavailable_s",
    "s",
    "roadgaze's choice",
    "no face, not explained by a turn away, this long",
)
DROWSY = Rule(
    "roadgaze.drowsy",
    "perclos_drowsy",
    "fraction",
    "PERCLOS P80 (Wierwille et al. 1994; Dinges et al. 1998); the level is roadgaze's choice",
    "PERCLOS at or above this",
    impairment=True,
)
FROZEN = Rule(
    "roadgaze.failure.frozen",
    "frozen_failure_s",
    "s",
    "EU 2023/2590 Annex I 3.5.2 (temporary failure); the time is roadgaze's choice, within "
    "Euro NCAP's 10 s for impaired monitoring",
    "identical frames this long: temporary failure",
)
NO_FACE = Rule(
    "roadgaze.failure.no_face",
    "no_face_failure_s",
    "s",
    "EU 2023/2590 Annex I 3.5.2 (temporary failure); the time is Euro NCAP's 10 s for impaired "
    "monitoring",
    "no judgeable face this long: temporary failure",
)
RULES = (CRITICAL, CLEAR, UNAVAILABLE, DROWSY, FROZEN, NO_FACE)
