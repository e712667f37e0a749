"""Euro NCAP 2026's driver-monitoring verification: the noise variables (the sheet's rows 2-13:
does the system work under each) and the general requirements (sheet "DE - DM verif."), and how
roadgaze answers each from measured scenarios. Pure data; the rows of the prediction sheet are
`roadgaze.conformance.dossier_rows`, which re-exports these names."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

from roadgaze.conformance.model import Scenario
from roadgaze.conformance.notices import notice_key

DROWSINESS_EVIDENCE = ("drowsy_70.warns", "alert_70.quiet", "drowsy_40.quiet")
"""Drowsiness' warning (row 68) and its activation speed: warned at 70 km/h, silent for an
alert driver at 70 km/h and for the drowsy one at 40 km/h (roadgaze.conformance.drowsiness)."""

Variant = Callable[[Scenario], Scenario]


def under(condition: str) -> Variant:
    """A function rendering a scenario under `condition` (a name of
    `roadgaze.synth.outfit.CONDITIONS`) from its first frame, run as `NAME__condition`."""

    def variant(scenario: Scenario) -> Scenario:
        conditions = (*scenario.conditions, condition)
        return replace(scenario, name=f"{scenario.name}__{condition}", conditions=conditions)

    variant.__name__ = variant.__qualname__ = condition
    variant.__doc__ = f"The scenario rendered under `{condition}` from its first frame."
    return variant


dark_sunglasses = under("dark_sunglasses")
"""The scenario with the driver in dark sunglasses from the first frame."""


@dataclass(frozen=True, slots=True)
class NoiseVariable:
    """A row of the sheet's noise-variable table: the system works ("Functional") or not under
    it. `variant` renders a scenario under it (None: roadgaze cannot render it yet, so it is
    not shown functional)."""

    row: int
    element: str
    mandatory: bool
    """The calculator scores Driver Monitoring 0 unless this one is Functional."""
    variant: Variant | None = None


NOISE_VARIABLES: tuple[NoiseVariable, ...] = (
    NoiseVariable(2, "Daytime - Night-time", True, under("night")),
    NoiseVariable(3, "Clear sunglasses", True, under("clear_sunglasses")),
    NoiseVariable(4, "Dark sunglasses", False, dark_sunglasses),
    NoiseVariable(5, "Short facial hair", True, under("stubble")),
    NoiseVariable(6, "Long facial hair", True, under("beard")),
    NoiseVariable(7, "Hand on wheel at 12 o'clock position", False, under("hand_at_12")),
    NoiseVariable(8, "Face-mask", True, under("mask")),
    NoiseVariable(9, "Cap", False, under("cap")),
    NoiseVariable(10, "Hat", False, under("hat")),
    NoiseVariable(11, "Long head hair fringe obscuring eyes", False, under("fringe")),
    NoiseVariable(12, "Thick eyelash makeup", False, under("eyelash_makeup")),
    NoiseVariable(13, "Talking", False, under("talking")),
)
"""The sheet's rows 2-13 ("Talking" is named in column B, the others in column C)."""


@dataclass(frozen=True, slots=True)
class GeneralRequirement:
    """A general requirement of the verification sheet ("DE - DM verif."), in the calculator's
    own words, and how roadgaze answers it: PASS when every `evidence` key passed; without
    evidence, PASS on `basis` (a property of the service) or on `integrator` (the vehicle's
    part, taken as met and printed with the score); N/A when `noise` names a noise variable
    the dossier states Functional; PASS when `every_speed` names a slow scenario that warned
    while the rules are configured active at every forward speed (`min_speed_kmh` 0: active at
    the protocol's activation speed, whatever it is); otherwise FAIL, `missing` saying what is
    not there."""

    text: str
    label: str
    """A few words for the score's summary."""
    evidence: tuple[str, ...] = ()
    basis: str = ""
    integrator: str = ""
    noise: str = ""
    missing: str = ""
    every_speed: str = ""


_INFORM = "Inform with visual and/or auditory cues of non functional system within 10 seconds"
_NO_NOTICE = "no non-functional notice measured"
_TOLD = "the service raised `non_functional` within 10 s of the condition's onset"
_SHOWN = (
    "while a notice lasts, every state message shows it (`monitor.non_functional`, "
    "roadgaze.state/6) and the alert is raised again every 10 minutes (non_functional_repeat_s)"
)


def _notice(when: str, label: str, condition: str, noise: str) -> GeneralRequirement:
    """The requirement to inform of a non-functional system within 10 s `when` (the sheet's
    words after its common start), answered by the notice scenario of `condition`, N/A when
    the noise variable `noise` is stated Functional."""
    return GeneralRequirement(
        f"{_INFORM} {when}",
        f"notice: {label}",
        (notice_key(condition),),
        basis=_TOLD,
        noise=noise,
        missing=_NO_NOTICE,
    )


GENERAL_REQUIREMENTS: tuple[GeneralRequirement, ...] = (
    GeneralRequirement(
        "Default ON at the start of every journey",
        "on by default",
        ("lap_70.warns",),
        basis="the service monitors from its first frame; no setting turns monitoring off",
    ),
    GeneralRequirement(
        "Deactivation is not possible with a momentary single push on a button",
        "no off by a single push",
        integrator="the service has no off switch; the vehicle's buttons are the integrator's",
    ),
    GeneralRequirement(
        "Detection sensitivity shall not be manually adjustable",
        "sensitivity not adjustable",
        integrator="the service takes no driver input; its settings are the integrator's",
    ),
    GeneralRequirement(
        "Continuous monitoring of the driver state",
        "continuous monitoring",
        ("vats_70.warns",),
        basis="every frame is judged: VATS adds up five glances over 15 s",
    ),
    GeneralRequirement(
        "Speed activation condition for the distraction, microsleep, sleep and unresponsive "
        "driver states",
        "speed activation of distraction, microsleep, sleep, unresponsive",
        missing="the protocol's activation speed was not read here; roadgaze's 20 km/h "
        "(min_speed_kmh) is its own choice",
        every_speed="lap_8s_10.quiet",
    ),
    GeneralRequirement(
        "Speed activation condition for the impairment driver states, when the vehicle is moving "
        "forward at a speed of at least 50 km/h",
        "speed activation of impairment (>= 50 km/h)",
        DROWSINESS_EVIDENCE,
        basis="drowsiness warns at 70 km/h and not at 40 km/h (drowsiness_min_speed_kmh 50); "
        "non-fatigue impairment is not detected (its row stays RED)",
    ),
    GeneralRequirement(
        "Assisted Driving prerequisite (≥50% of Driving collaboration and ≥50% of Driver "
        "monitoring)",
        "assisted driving prerequisite",
        integrator="assisted driving and its driving collaboration are the vehicle's",
    ),
    _notice(
        "after the driver obstructs the sensor by gripping the upper portion of the steering wheel",
        "hand on the wheel at 12 o'clock",
        "hand_at_12",
        "Hand on wheel at 12 o'clock position",
    ),
    _notice("after the driver wears a cap", "cap", "cap", "Cap"),
    _notice("after the driver wears a hat", "hat", "hat", "Hat"),
    _notice(
        "after the driver wears dark sunglasses",
        "dark sunglasses",
        "dark_sunglasses",
        "Dark sunglasses",
    ),
    _notice(
        "for a driver with long head hair fringe obscuring eyes",
        "hair fringe",
        "fringe",
        "Long head hair fringe obscuring eyes",
    ),
    _notice(
        "for a driver with thick eyelash makeup",
        "eyelash makeup",
        "eyelash_makeup",
        "Thick eyelash makeup",
    ),
    GeneralRequirement(
        "Visual information about non-functional system shown permanently or every [10] minutes",
        "notice shown permanently or every 10 minutes",
        (notice_key("dark_sunglasses"),),
        basis=_SHOWN,
        missing=_NO_NOTICE,
    ),
)
