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

from dataclasses import dataclass, replace

from roadgaze.conformance.dossier_general import (
    DROWSINESS_EVIDENCE,
    GENERAL_REQUIREMENTS,
    NOISE_VARIABLES,
    GeneralRequirement,
    NoiseVariable,
    Variant,
    dark_sunglasses,
    under,
)
from roadgaze.conformance.locations import PHONE_LOOKS, look_name
from roadgaze.conformance.support import SHEET_ROWS
from roadgaze.monitor.protocols import Rule, euroncap, support

__all__ = [
    "ASSUMPTIONS",
    "CELL_COLUMNS",
    "DROWSINESS",
    "GENERAL_REQUIREMENTS",
    "NA",
    "NOISE_VARIABLES",
    "NON_TRANSIENT",
    "NON_TRANSIENT_HEADERS",
    "ROWS",
    "SHEET",
    "TABLES",
    "TRANSIENT_HEADERS",
    "Evidence",
    "GeneralRequirement",
    "NoiseVariable",
    "SheetRow",
    "Variant",
    "dark_sunglasses",
    "key_for",
    "row_at",
    "under",
]
"""Public names; the noise variables and general requirements live in
roadgaze.conformance.dossier_general and are re-exported here."""

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


def _phone_look(row: int, task: str, location: str) -> SheetRow:
    """A phone row measured by a look at the phone (`PHONE_LOOKS`): its warning cell."""
    movement, place = PHONE_LOOKS[row]
    warns = (f"{look_name(movement, place)}.warns",)
    return _row(row, PHONE, task, movement.capitalize(), location, LD, warns)


_PHONE_USE = (euroncap.PHONE_USE,)
_WHEEL, _SCREEN = ("phone_wheel_70.warns",), ("phone_windscreen_70.warns",)
_CLUSTER = ("phone_cluster_70.warns",)
_PHONE_ROWS = (
    # A look at the phone where it lies (roadgaze.conformance.locations.PHONE_LOOKS).
    _phone_look(51, BASIC, "Phone mounted on dashboard outboard"),
    _phone_look(52, BASIC, "Driver knee outboard"),
    _phone_look(53, BASIC, "Driver lap"),
    _phone_look(54, BASIC, "Driver inboard"),
    _phone_look(55, BASIC, "Phone mounted on dedicated position"),
    _phone_look(56, BASIC, "Driver knee outboard"),
    _phone_look(57, BASIC, "Driver lap"),
    _phone_look(58, BASIC, "Driver inboard"),
    _phone_look(59, BASIC, "Phone mounted on dedicated position"),
    _phone_look(60, BASIC, "Phone held centre of steering wheel"),
    _phone_look(61, ADVANCED, "Phone mounted on dashboard outboard"),
    # A phone held up (roadgaze.conformance.phone): the hand seen, the eyes on the phone.
    _row(62, PHONE, ADVANCED, "Lizard", "Phone held in 9-11 or 1-3 o'clock", _PHONE_USE, _WHEEL),
    _row(63, PHONE, ADVANCED, "Lizard", "Phone held in view of windscreen", _PHONE_USE, _SCREEN),
    _row(
        64,
        PHONE,
        ADVANCED,
        "Lizard",
        "Phone held in view of instrument cluster",
        _PHONE_USE,
        _CLUSTER,
    ),
)
# Drowsiness (impairment by fatigue): roadgaze.conformance.drowsiness.
DROWSINESS = (euroncap.DROWSINESS, euroncap.DROWSINESS_SPEED)
_MICROSLEEP = ("microsleep_70.warns", "microsleep_70.no_sleep")
_UNRESPONSIVE = ("unresponsive_closed_70.warns", "unresponsive_away_70.warns")
_NON_TRANSIENT_ROWS = (
    _row(
        68, NON_TRANSIENT, "Impairment", "", "Drowsiness", DROWSINESS, DROWSINESS_EVIDENCE, (), NA
    ),
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
