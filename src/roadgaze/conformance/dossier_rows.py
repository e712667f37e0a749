"""Euro NCAP 2026's driver-monitoring prediction sheet, row by row, and what roadgaze measures
for each of its cells. Pure data.

The sheet is "DE - DM pred." of the Safe Driving template of Euro NCAP's rating calculator
(`euroncap-rating-2026`, `data/sd_template.xlsx`). Each `SheetRow` is one row of it: where it is
(the sheet's own row number), what it names (table, task, movement type, gaze location or
impairment type), the protocol rules roadgaze runs for it, and for each of its three cells the
conformance requirements (`Requirement.key` of `roadgaze.conformance.matrix`) that must all PASS
for the cell to be GREEN. `()` means nothing measures the cell yet (RED); `NA` marks a cell the
sheet leaves out (no input: a driving-task glance earns no warning points). `{driver}` and
`{passenger}` in a key stand for the cabin's sides (`left`/`right` in a left-hand-drive cabin).

**Adding a scenario for a row is adding its requirement key to that row's tuple.**
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

from roadgaze.conformance.model import Scenario
from roadgaze.conformance.notices import notice_key
from roadgaze.conformance.support import SHEET_ROWS
from roadgaze.monitor.protocols import Rule, euroncap, support

SHEET = "DE - DM pred."
"""The prediction sheet's name in the template."""

Evidence = tuple[str, ...] | None
"""The requirement keys a cell needs, all PASS; `()` nothing yet; `NA` not in the sheet."""
NA: Evidence = None

LONG, SHORT, PHONE, NON_TRANSIENT = (
    "Long distraction",
    "Short distraction",
    "Phone use",
    "Non-transient",
)
TABLES = {LONG: 15, SHORT: 33, PHONE: 49, NON_TRANSIENT: 66}
"""Each table's title row in the sheet (the column headers are on the row after it)."""
CELL_COLUMNS = ("D", "E", "F")
TRANSIENT_HEADERS = ("Warning", "Forward support", "Lane support")
NON_TRANSIENT_HEADERS = ("Warning", "Forward and lane support", "Emergency function")

LD, VATS = (euroncap.LONG_DISTRACTION,), (euroncap.VATS,)
UNRESPONSIVE = (euroncap.UNRESPONSIVE_CLOSED, euroncap.UNRESPONSIVE_AFTER_WARNING)


@dataclass(frozen=True, slots=True)
class SheetRow:
    """One row of the prediction sheet and the evidence behind each of its three cells."""

    row: int
    table: str
    task: str
    """Column A: "Non-driving task", "Driving task", "Multi-target", "Basic phone use", ...;
    in the non-transient table "Impairment", "Microsleep", "Sleep", "Unresponsive"."""
    movement: str
    """Column B: "Owl", "Lizard", "Body lean" ("" in the non-transient table)."""
    location: str
    """Column C: the gaze location, or the impairment type ("" where the sheet has none)."""
    rules: tuple[Rule, ...]
    """The protocol rules roadgaze runs for the row (empty: no behaviour yet)."""
    cells: tuple[Evidence, Evidence, Evidence]
    """Warning, forward support, lane support (non-transient: warning, forward and lane
    support, emergency function)."""

    @property
    def headers(self) -> tuple[str, str, str]:
        return NON_TRANSIENT_HEADERS if self.table == NON_TRANSIENT else TRANSIENT_HEADERS

    @property
    def name(self) -> str:
        """The row as the sheet reads it: task / movement / location."""
        return " / ".join(part for part in (self.task, self.movement, self.location) if part)


def _row(
    row: int,
    table: str,
    task: str,
    movement: str,
    location: str,
    rules: tuple[Rule, ...],
    warning: Evidence = (),
    forward: Evidence = (),
    lane: Evidence = (),
) -> SheetRow:
    return SheetRow(row, table, task, movement, location, rules, (warning, forward, lane))


ND, DT = "Non-driving task", "Driving task"
_LIZARD_INFOTAINMENT = ("lizard_infotainment_70.warns",)
_LEAN_FOOTWELL = ("lean_passenger_footwell_70.warns", "lean_road_70.warns")
"""A lean toward the footwell warns, and so does a lean that keeps the face to the road (the
head's place is measured, not only where it faces)."""
_LONG_ROWS = (
    _row(17, LONG, ND, "Owl", "Driver side window", LD, ("side_{driver}_70.warns",)),
    _row(18, LONG, ND, "Owl", "In-vehicle infotainment system", LD, ("centre_stack_70.warns",)),
    # Gaze locations (roadgaze.cabin, scenarios: roadgaze.conformance.locations).
    _row(19, LONG, ND, "Owl", "Passenger footwell", LD, ("owl_passenger_footwell_70.warns",)),
    _row(20, LONG, ND, "Owl", "Passenger face", LD, ("owl_passenger_face_70.warns",)),
    _row(21, LONG, ND, "Owl", "Passenger side window", LD, ("side_{passenger}_70.warns",)),
    _row(22, LONG, ND, "Lizard", "In-vehicle infotainment system", LD, _LIZARD_INFOTAINMENT),
    _row(23, LONG, ND, "Lizard", "Glovebox", LD, ("lizard_glovebox_70.warns",)),
    _row(24, LONG, ND, "Body lean", "Passenger footwell", LD, _LEAN_FOOTWELL),
    _row(25, LONG, ND, "Body lean", "Rear passenger", LD, ("lean_rear_passenger_70.warns",)),
    _row(26, LONG, DT, "Owl", "Driver side mirror", (), NA),
    _row(27, LONG, DT, "Owl", "Rear view mirror", (), NA),
    _row(28, LONG, DT, "Owl", "Passenger side mirror", (), NA),
    _row(29, LONG, DT, "Lizard", "Driver side mirror", (), NA),
    _row(30, LONG, DT, "Lizard", "Instrument cluster", (), NA),
    _row(31, LONG, DT, "Lizard", "Rear view mirror", (), NA),
)
_VATS_INFOTAINMENT = ("vats_70.warns", "vats_70.no_long", "vats_below_70.quiet")


def _vats(glances: str) -> tuple[str, ...]:
    """A short-distraction row's evidence: its glances add up to VATS, none warns on its own."""
    return (f"vats_{glances}_70.warns", f"vats_{glances}_70.no_long")


_SHORT_ROWS = (
    _row(35, SHORT, ND, "Owl", "In-vehicle infotainment system", VATS, _VATS_INFOTAINMENT),
    # Gaze locations (roadgaze.cabin, scenarios: roadgaze.conformance.locations).
    _row(36, SHORT, ND, "Owl", "Passenger footwell", VATS, _vats("owl_passenger_footwell")),
    _row(
        37,
        SHORT,
        ND,
        "Lizard",
        "In-vehicle infotainment system",
        VATS,
        _vats("lizard_infotainment"),
    ),
    _row(38, SHORT, ND, "Lizard", "Passenger footwell", VATS, _vats("lizard_passenger_footwell")),
    _row(39, SHORT, DT, "Owl", "Driver side mirror", (), NA),
    _row(40, SHORT, DT, "Owl", "Rear view mirror", (), NA),
    _row(41, SHORT, DT, "Owl", "Passenger side mirror", (), NA),
    _row(42, SHORT, DT, "Owl", "Passenger side window", (), NA),
    _row(43, SHORT, DT, "Lizard", "Driver side window", (), NA),
    _row(44, SHORT, DT, "Lizard", "Driver side mirror", (), NA),
    _row(45, SHORT, DT, "Lizard", "Instrument cluster", (), NA),
    _row(46, SHORT, DT, "Lizard", "Rear view mirror", (), NA),
    _row(47, SHORT, "Multi-target", "Lizard", "", VATS, _vats("lizard_multi_target")),
)
BASIC, ADVANCED = "Basic phone use", "Advanced phone use"
_DASH, _MOUNT, _KNEE, _HUB = (
    "phone_dashboard_outboard",
    "phone_dedicated_mount",
    "driver_knee_outboard",
    "phone_wheel_centre",
)


def _look(movement: str, place: str) -> tuple[str, ...]:
    """A phone row's warning evidence: a 4 s look at the phone by `movement` warns."""
    return (f"{movement}_{place}_70.warns",)


_PHONE_USE = (euroncap.PHONE_USE,)
_WHEEL, _SCREEN = ("phone_wheel_70.warns",), ("phone_windscreen_70.warns",)
_PHONE_ROWS = (
    # A look at the phone where it lies (roadgaze.conformance.locations.PHONE_LOOKS).
    _row(51, PHONE, BASIC, "Owl", "Phone mounted on dashboard outboard", LD, _look("owl", _DASH)),
    _row(52, PHONE, BASIC, "Owl", "Driver knee outboard", LD, _look("owl", "driver_knee_outboard")),
    _row(53, PHONE, BASIC, "Owl", "Driver lap", LD, _look("owl", "driver_lap")),
    _row(54, PHONE, BASIC, "Owl", "Driver inboard", LD, _look("owl", "driver_inboard")),
    _row(55, PHONE, BASIC, "Owl", "Phone mounted on dedicated position", LD, _look("owl", _MOUNT)),
    _row(56, PHONE, BASIC, "Lizard", "Driver knee outboard", LD, _look("lizard", _KNEE)),
    _row(57, PHONE, BASIC, "Lizard", "Driver lap", LD, _look("lizard", "driver_lap")),
    _row(58, PHONE, BASIC, "Lizard", "Driver inboard", LD, _look("lizard", "driver_inboard")),
    _row(
        59,
        PHONE,
        BASIC,
        "Lizard",
        "Phone mounted on dedicated position",
        LD,
        _look("lizard", _MOUNT),
    ),
    _row(
        60, PHONE, BASIC, "Lizard", "Phone held centre of steering wheel", LD, _look("lizard", _HUB)
    ),
    _row(
        61,
        PHONE,
        ADVANCED,
        "Lizard",
        "Phone mounted on dashboard outboard",
        LD,
        _look("lizard", _DASH),
    ),
    # A phone held up (roadgaze.conformance.phone): the hand seen, the eyes on the phone.
    _row(62, PHONE, ADVANCED, "Lizard", "Phone held in 9-11 or 1-3 o'clock", _PHONE_USE, _WHEEL),
    _row(63, PHONE, ADVANCED, "Lizard", "Phone held in view of windscreen", _PHONE_USE, _SCREEN),
    _row(64, PHONE, ADVANCED, "Lizard", "Phone held in view of instrument cluster", ()),
)
# Drowsiness (impairment by fatigue): roadgaze.conformance.drowsiness.
DROWSINESS = (euroncap.DROWSINESS, euroncap.DROWSINESS_SPEED)
_DROWSINESS = ("drowsy_70.warns", "alert_70.quiet", "drowsy_40.quiet")
_MICROSLEEP = ("microsleep_70.warns", "microsleep_70.no_sleep")
_UNRESPONSIVE = ("unresponsive_closed_70.warns", "unresponsive_away_70.warns")
_NON_TRANSIENT_ROWS = (
    _row(68, NON_TRANSIENT, "Impairment", "", "Drowsiness", DROWSINESS, _DROWSINESS, (), NA),
    _row(69, NON_TRANSIENT, "Impairment", "", "Non-fatigue", (), (), (), NA),
    _row(70, NON_TRANSIENT, "Microsleep", "", "", (euroncap.MICROSLEEP,), _MICROSLEEP, (), NA),
    _row(71, NON_TRANSIENT, "Sleep", "", "", (euroncap.SLEEP,), ("sleep_70.warns",), (), NA),
    _row(72, NON_TRANSIENT, "Unresponsive", "", "", UNRESPONSIVE, NA, NA, _UNRESPONSIVE),
)

# Forward and lane support (roadgaze.conformance.support): the scenario whose support is judged
# for each row, and the rules behind it. `support_forward` for the forward cell, `support_lane`
# for the lane cell; the non-transient rows' one cell needs both (`support.SHEET_ROWS`).
_FORWARD, _LANE = support.support_rules(support.FORWARD), support.support_rules(support.LANE)


def _with_support(row: SheetRow) -> SheetRow:
    scenario = SHEET_ROWS.get(row.row)
    if scenario is None:
        return row
    forward, lane = f"{scenario}.support_forward", f"{scenario}.support_lane"
    warning, _, third = row.cells
    if row.table == NON_TRANSIENT:
        rules = (_FORWARD.impaired, _LANE.impaired)
        return replace(row, rules=(*row.rules, *rules), cells=(warning, (forward, lane), third))
    rules = (_FORWARD.off_road, _LANE.off_road)
    return replace(row, rules=(*row.rules, *rules), cells=(warning, (forward,), (lane,)))


ROWS: tuple[SheetRow, ...] = tuple(
    _with_support(row) for row in (*_LONG_ROWS, *_SHORT_ROWS, *_PHONE_ROWS, *_NON_TRANSIENT_ROWS)
)
"""Every row of the sheet that takes a prediction, in sheet order."""


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
    the dossier states Functional; otherwise FAIL, `missing` saying what is not there."""

    text: str
    label: str
    """A few words for the score's summary."""
    evidence: tuple[str, ...] = ()
    basis: str = ""
    integrator: str = ""
    noise: str = ""
    missing: str = ""


_INFORM = "Inform with visual and/or auditory cues of non functional system within 10 seconds"
_NO_NOTICE = "no non-functional notice measured"
_TOLD = "the service raised `non_functional` within 10 s of the condition's onset"
_SHOWN = (
    "while a notice lasts, every state message shows it (`monitor.non_functional`, "
    "roadgaze.state/6) and the alert is raised again every 10 minutes (non_functional_repeat_s)"
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
    ),
    GeneralRequirement(
        "Speed activation condition for the impairment driver states, when the vehicle is moving "
        "forward at a speed of at least 50 km/h",
        "speed activation of impairment (>= 50 km/h)",
        _DROWSINESS,
        basis="drowsiness warns at 70 km/h and not at 40 km/h (drowsiness_min_speed_kmh 50); "
        "non-fatigue impairment is not detected (its row stays RED)",
    ),
    GeneralRequirement(
        "Assisted Driving prerequisite (≥50% of Driving collaboration and ≥50% of Driver "
        "monitoring)",
        "assisted driving prerequisite",
        integrator="assisted driving and its driving collaboration are the vehicle's",
    ),
    GeneralRequirement(
        f"{_INFORM} after the driver obstructs the sensor by gripping the upper portion of the "
        "steering wheel",
        "notice: hand on the wheel at 12 o'clock",
        (notice_key("hand_at_12"),),
        basis=_TOLD,
        noise="Hand on wheel at 12 o'clock position",
        missing=_NO_NOTICE,
    ),
    GeneralRequirement(
        f"{_INFORM} after the driver wears a cap",
        "notice: cap",
        (notice_key("cap"),),
        basis=_TOLD,
        noise="Cap",
        missing=_NO_NOTICE,
    ),
    GeneralRequirement(
        f"{_INFORM} after the driver wears a hat",
        "notice: hat",
        (notice_key("hat"),),
        basis=_TOLD,
        noise="Hat",
        missing=_NO_NOTICE,
    ),
    GeneralRequirement(
        f"{_INFORM} after the driver wears dark sunglasses",
        "notice: dark sunglasses",
        (notice_key("dark_sunglasses"),),
        basis=_TOLD,
        noise="Dark sunglasses",
        missing=_NO_NOTICE,
    ),
    GeneralRequirement(
        f"{_INFORM} for a driver with long head hair fringe obscuring eyes",
        "notice: hair fringe",
        (notice_key("fringe"),),
        basis=_TOLD,
        noise="Long head hair fringe obscuring eyes",
        missing=_NO_NOTICE,
    ),
    GeneralRequirement(
        f"{_INFORM} for a driver with thick eyelash makeup",
        "notice: eyelash makeup",
        (notice_key("eyelash_makeup"),),
        basis=_TOLD,
        noise="Thick eyelash makeup",
        missing=_NO_NOTICE,
    ),
    GeneralRequirement(
        "Visual information about non-functional system shown permanently or every [10] minutes",
        "notice shown permanently or every 10 minutes",
        (notice_key("dark_sunglasses"),),
        basis=_SHOWN,
        missing=_NO_NOTICE,
    ),
)

ASSUMPTIONS = (
    "forward and lane support count the service's support request (the vehicle's reaction is "
    "the integrator's)",
    "the emergency function counts the service's `unresponsive` alert as its request (the "
    "vehicle's manoeuvre is the integrator's)",
)
"""Printed with every score: what the service's part is taken to stand for."""


def key_for(key: str, cabin: str) -> str:
    """`key` with `{driver}` and `{passenger}` replaced by the cabin's sides."""
    driver, passenger = ("left", "right") if cabin == "lhd" else ("right", "left")
    return key.replace("{driver}", driver).replace("{passenger}", passenger)


def row_at(row: int) -> SheetRow | None:
    """The sheet row at `row` (None: not a prediction row)."""
    return next((r for r in ROWS if r.row == row), None)
