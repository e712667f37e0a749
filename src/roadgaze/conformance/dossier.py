"""The Euro NCAP driver-monitoring dossier judged from a conformance run: each cell of the
prediction sheet GREEN only where every requirement behind it was measured passing, as rendered
and again under every noise variable that must be Functional for a score at all (the mandatory
ones, and those whose non-functional notice the service did not give), each other noise
variable Functional only where every GREEN cell also passed under it, each general requirement
answered with its basis. Pure: the scenarios that must be run again (under a noise variable,
or for the calculator's verification) go through a `Runner` the caller gives.

The table of rows, noise variables and general requirements: `roadgaze.conformance.dossier_rows`;
the workbook: `dossier_xlsx`; the official calculator: `dossier_score`.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, replace

from roadgaze.conformance.dossier_rows import (
    CELL_COLUMNS,
    GENERAL_REQUIREMENTS,
    NOISE_VARIABLES,
    ROWS,
    GeneralRequirement,
    NoiseVariable,
    SheetRow,
    key_for,
)
from roadgaze.conformance.model import Outcome, Scenario

Runner = Callable[[Sequence[Scenario]], Sequence[Outcome]]
"""Runs scenarios through the service and returns their outcomes (the conformance suite's)."""
GREEN, RED = "Green", "Red"
FUNCTIONAL, NON_FUNCTIONAL = "Functional", "Non Functional"


@dataclass(frozen=True, slots=True)
class Cell:
    """One cell of the prediction sheet: its colour (None: the sheet leaves it out) and why."""

    row: SheetRow
    index: int
    """0, 1, 2: the sheet's columns D, E, F."""
    colour: str | None
    keys: tuple[str, ...]
    """The requirement keys behind it, for this cabin."""
    why: str

    @property
    def column(self) -> str:
        return CELL_COLUMNS[self.index]

    @property
    def header(self) -> str:
        return self.row.headers[self.index]


@dataclass(frozen=True, slots=True)
class NoiseVerdict:
    variable: NoiseVariable
    functional: bool
    why: str

    @property
    def performance(self) -> str:
        """The sheet's value: "Functional" or "Non Functional"."""
        return FUNCTIONAL if self.functional else NON_FUNCTIONAL


@dataclass(frozen=True, slots=True)
class GeneralVerdict:
    requirement: GeneralRequirement
    value: str
    """PASS, FAIL or N/A (the calculator's accepted answers)."""
    why: str


@dataclass(frozen=True, slots=True)
class Dossier:
    """The judged sheet: every prediction cell, noise variable and general requirement."""

    cells: tuple[Cell, ...]
    noise: tuple[NoiseVerdict, ...]
    general: tuple[GeneralVerdict, ...]
    cabin: str

    def cell(self, row: int, column: str) -> Cell | None:
        """The prediction cell at sheet row `row`, column letter `column` (None: none)."""
        return next((c for c in self.cells if c.row.row == row and c.column == column), None)

    def noise_of(self, element: str) -> NoiseVerdict | None:
        return next((n for n in self.noise if n.variable.element == element), None)

    def gates(self) -> list[str]:
        """What holds the calculator's Driver Monitoring score at 0 whatever the rows earn."""
        held = [n.variable.element for n in self.noise if n.variable.mandatory and not n.functional]
        failed = [g.requirement.label for g in self.general if g.value == "FAIL"]
        gates = []
        if held:
            gates.append(f"mandatory noise variables not shown functional: {', '.join(held)}")
        if failed:
            noun = "requirement" if len(failed) == 1 else "requirements"
            gates.append(f"{len(failed)} general {noun} not met: {'; '.join(failed)}")
        return gates


def outcomes_by_key(outcomes: Iterable[Outcome]) -> dict[str, Outcome]:
    """The outcomes by requirement key (the last one of a key wins)."""
    return {outcome.requirement.key: outcome for outcome in outcomes}


def _measured(outcome: Outcome) -> str:
    measured = "none" if outcome.measured_s is None else f"{outcome.measured_s:.2f} s"
    return f"{outcome.requirement.key} {measured}"


def verdict(keys: tuple[str, ...], results: dict[str, Outcome]) -> tuple[bool, str]:
    """(passed, why) for a cell needing `keys`: every one run and PASS (N/A is not a pass)."""
    if not keys:
        return False, "no scenario measures it yet"
    missing = [key for key in keys if key not in results]
    if missing:
        return False, f"not run: {', '.join(missing)}"
    failed = [results[key] for key in keys if results[key].result != "PASS"]
    if failed:
        return False, "FAIL: " + ", ".join(f"{_measured(o)} ({o.result})" for o in failed)
    return True, "PASS: " + ", ".join(_measured(results[key]) for key in keys)


def judge_cells(results: dict[str, Outcome], cabin: str) -> tuple[Cell, ...]:
    """Every prediction cell of the sheet from the run's outcomes."""
    cells = []
    for row in ROWS:
        for index, evidence in enumerate(row.cells):
            if evidence is None:
                cells.append(Cell(row, index, None, (), "not in the sheet"))
                continue
            keys = tuple(key_for(key, cabin) for key in evidence)
            passed, why = verdict(keys, results)
            cells.append(Cell(row, index, GREEN if passed else RED, keys, why))
    return tuple(cells)


def scenarios_of(keys: Iterable[str], scenarios: Sequence[Scenario]) -> list[Scenario]:
    """The scenarios that hold `keys`, each once, in matrix order."""
    wanted = set(keys)
    return [s for s in scenarios if any(r.key in wanted for r in s.requirements)]


def _shortest_first(keys: Iterable[str], scenarios: Sequence[Scenario]) -> list[Scenario]:
    """The scenarios behind `keys`, the shortest drive first (a failure shows soonest)."""
    return sorted(scenarios_of(keys, scenarios), key=lambda s: s.duration_s)


def run_under(
    keys: tuple[str, ...],
    noise: NoiseVariable | None,
    scenarios: Sequence[Scenario],
    runner: Runner,
) -> tuple[bool, str]:
    """Run the scenarios behind `keys` again, under `noise` (None: as they are), one by one,
    the shortest drive first, stopping at the first that fails; (passed, why)."""
    if noise is not None and noise.variant is None:
        return False, f"roadgaze cannot render {noise.element!r} yet"
    results: dict[str, Outcome] = {}
    for scenario in _shortest_first(keys, scenarios):
        run = scenario if noise is None or noise.variant is None else noise.variant(scenario)
        results.update(outcomes_by_key(runner([run])))
        passed, why = verdict(tuple(k for k in keys if k in results), results)
        if not passed:
            return False, f"{run.name}: {why}"
    return verdict(keys, results)


def _green_keys(cells: Sequence[Cell]) -> tuple[str, ...]:
    return tuple(dict.fromkeys(k for c in cells if c.colour == GREEN for k in c.keys))


def must_hold(variable: NoiseVariable, results: dict[str, Outcome]) -> str:
    """Why every GREEN cell must pass under `variable` ("": it may be Non Functional): it is
    mandatory, or it asks for a non-functional notice and the run measured none (Non Functional,
    it would then fail that general requirement; a notice scenario not run says nothing).
    Either way the calculator would score 0."""
    if variable.mandatory:
        return "mandatory"
    notices = [r for r in GENERAL_REQUIREMENTS if r.noise == variable.element and r.evidence]
    measured = [r for r in notices if all(key in results for key in r.evidence)]
    if any(not verdict(r.evidence, results)[0] for r in measured):
        return "no notice given"
    return ""


def hold_under_required(
    cells: Sequence[Cell],
    scenarios: Sequence[Scenario],
    runner: Runner,
    results: dict[str, Outcome],
) -> tuple[tuple[Cell, ...], dict[str, dict[str, Outcome]]]:
    """The cells with every GREEN one that fails under a noise variable that `must_hold` turned
    RED (saying under which, and why it must hold), and each such variable's outcomes: every
    scenario behind a GREEN cell run again under it (not stopping at the first failure). A row
    the system meets only outside a condition it must work in is not claimed, as a carmaker
    would not claim it: claimed, the condition would score 0."""
    judged: tuple[Cell, ...] = tuple(cells)
    measured: dict[str, dict[str, Outcome]] = {}
    for variable in NOISE_VARIABLES:
        reason = must_hold(variable, results)
        if not reason or variable.variant is None:
            continue
        again: dict[str, Outcome] = {}
        for scenario in _shortest_first(_green_keys(judged), scenarios):
            again.update(outcomes_by_key(runner([variable.variant(scenario)])))
        measured[variable.element] = again
        held = []
        for cell in judged:
            passed, why = (True, "") if cell.colour != GREEN else verdict(cell.keys, again)
            if not passed:
                under = f"RED under {variable.element} ({reason}): {why}"
                cell = replace(cell, colour=RED, why=f"{cell.why}; {under}")
            held.append(cell)
        judged = tuple(held)
    return judged, measured


def judge_noise(
    cells: Sequence[Cell],
    scenarios: Sequence[Scenario],
    runner: Runner,
    measured: dict[str, dict[str, Outcome]] | None = None,
) -> tuple[NoiseVerdict, ...]:
    """Each noise variable: Functional only where every GREEN cell's requirements pass again
    with the scenarios rendered under it. `measured`: outcomes already run under a variable (by
    `hold_under_required`), judged instead of running again."""
    green_keys = _green_keys(cells)
    verdicts = []
    for variable in NOISE_VARIABLES:
        if variable.variant is None:
            why = "not rendered by roadgaze yet: not shown functional"
            verdicts.append(NoiseVerdict(variable, False, why))
        elif not green_keys:
            verdicts.append(NoiseVerdict(variable, False, "no GREEN cell to show it on"))
        elif measured is not None and variable.element in measured:
            passed, why = verdict(green_keys, measured[variable.element])
            verdicts.append(NoiseVerdict(variable, passed, why))
        else:
            passed, why = run_under(green_keys, variable, scenarios, runner)
            verdicts.append(NoiseVerdict(variable, passed, why))
    return tuple(verdicts)


def _every_speed(key: str, results: dict[str, Outcome], min_speed_kmh: float | None) -> str:
    """Why the rules are shown active at every forward speed ("": not shown)."""
    slow = results.get(key)
    if min_speed_kmh != 0 or slow is None or slow.measured_s is None:
        return ""
    return (
        "min_speed_kmh 0: the rules are active at every forward speed, so at the protocol's "
        f"activation speed whatever it is ({slow.scenario} warned {slow.measured_s:.2f} s into "
        "its look)"
    )


def judge_general(
    results: dict[str, Outcome],
    noise: Sequence[NoiseVerdict],
    min_speed_kmh: float | None = None,
) -> tuple[GeneralVerdict, ...]:
    """Each general requirement answered (see `GeneralRequirement`); `min_speed_kmh`: the
    configured activation speed of the Euro NCAP rules (None: not known)."""
    functional = {n.variable.element for n in noise if n.functional}
    verdicts = []
    for requirement in GENERAL_REQUIREMENTS:
        every = _every_speed(requirement.every_speed, results, min_speed_kmh)
        if every:
            verdicts.append(GeneralVerdict(requirement, "PASS", every))
        elif requirement.noise and requirement.noise in functional:
            why = f"{requirement.noise} is Functional: nothing to inform of"
            verdicts.append(GeneralVerdict(requirement, "N/A", why))
        elif requirement.evidence:
            passed, why = verdict(requirement.evidence, results)
            basis = f"{requirement.basis} ({why})" if passed else why
            verdicts.append(GeneralVerdict(requirement, "PASS" if passed else "FAIL", basis))
        elif requirement.basis or requirement.integrator:
            why = requirement.basis or f"taken as met: {requirement.integrator}"
            verdicts.append(GeneralVerdict(requirement, "PASS", why))
        else:
            verdicts.append(GeneralVerdict(requirement, "FAIL", requirement.missing))
    return tuple(verdicts)


def judge(
    outcomes: Iterable[Outcome],
    scenarios: Sequence[Scenario],
    runner: Runner,
    cabin: str,
    min_speed_kmh: float | None = None,
) -> Dossier:
    """The dossier of a conformance run (`outcomes` of `scenarios`, in a `cabin`); scenarios
    are run again under each noise variable roadgaze can render, a GREEN cell kept only where
    it passes under every one that must hold (`hold_under_required`). `min_speed_kmh`: the
    configured activation speed of the Euro NCAP rules (`judge_general`)."""
    results = outcomes_by_key(outcomes)
    cells, measured = hold_under_required(judge_cells(results, cabin), scenarios, runner, results)
    noise = judge_noise(cells, scenarios, runner, measured)
    return Dossier(cells, noise, judge_general(results, noise, min_speed_kmh), cabin)


def with_gates_met(dossier: Dossier) -> Dossier:
    """The same cells with the mandatory noise variables Functional and every general
    requirement met: what the rows alone would earn (never written as the dossier)."""
    noise = tuple(
        NoiseVerdict(n.variable, True, "taken as met") if n.variable.mandatory else n
        for n in dossier.noise
    )
    general = tuple(GeneralVerdict(g.requirement, "PASS", "taken as met") for g in dossier.general)
    return Dossier(dossier.cells, noise, general, dossier.cabin)
