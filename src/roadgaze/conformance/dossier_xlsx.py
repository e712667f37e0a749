"""The dossier as Euro NCAP's own workbook: the Safe Driving template's driver-monitoring
prediction sheet checked and filled, the calculator's verification sheet read and answered, its
report's Driver Monitoring score read back. openpyxl (installed with `roadgaze[euroncap]`).

The template is never a file of this repository: it is the one the installed calculator
generates (`dossier_score.Calculator.template`). The prediction cells take the sheet's dropdown
values as text ("Green", "Red"; the noise variables "Functional", "Non Functional"), which is
what the calculator reads first; the cells the sheet leaves out are left as they are.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from roadgaze.conformance.dossier import Dossier
from roadgaze.conformance.dossier_rows import (
    CELL_COLUMNS,
    NOISE_VARIABLES,
    NON_TRANSIENT,
    NON_TRANSIENT_HEADERS,
    ROWS,
    SHEET,
    TABLES,
    TRANSIENT_HEADERS,
)
from roadgaze.errors import ConfigError

VERIFICATION = "DE - DM verif."
PREDICTION_LIST = '"N/A,Green,Red"'
"""The dropdown of every prediction cell the sheet asks for."""
NOISE_COLUMN = "D"
TEST_POINT = re.compile(r"\(\s*(\d+)\s*,\s*(\d+)\s*\)")


def _text(value: Any) -> str:
    return "" if value is None else str(value).strip()


def _unexpected(row: int, column: str, expected: str, found: Any) -> ConfigError:
    return ConfigError(
        f"Euro NCAP's template does not have the sheet roadgaze reads: {SHEET!r} cell "
        f"{column}{row} holds {_text(found)!r}, expected {expected!r}; install the pinned "
        "calculator (pip install -c constraints.txt 'roadgaze[euroncap]')"
    )


def _prediction_cells(ws: Any) -> set[str]:
    """The coordinates inside the sheet's "N/A,Green,Red" dropdowns."""
    from openpyxl.utils import get_column_letter

    cells: set[str] = set()
    for validation in ws.data_validations.dataValidation:
        if validation.formula1 != PREDICTION_LIST:
            continue
        for area in validation.sqref.ranges:
            for row in range(area.min_row, area.max_row + 1):
                for column in range(area.min_col, area.max_col + 1):
                    cells.add(f"{get_column_letter(column)}{row}")
    return cells


def check_template(wb: Any) -> Any:
    """The prediction sheet of `wb`, after checking that every table, noise variable, row and
    input cell is where `dossier_rows` says; one-line `ConfigError` naming what was found."""
    if SHEET not in wb.sheetnames:
        raise ConfigError(
            f"Euro NCAP's template has no sheet {SHEET!r} (found {', '.join(wb.sheetnames)}); "
            "install the pinned calculator (pip install -c constraints.txt 'roadgaze[euroncap]')"
        )
    ws = wb[SHEET]
    for table, row in TABLES.items():
        if _text(ws[f"A{row}"].value) != table:
            raise _unexpected(row, "A", table, ws[f"A{row}"].value)
        headers = NON_TRANSIENT_HEADERS if table == NON_TRANSIENT else TRANSIENT_HEADERS
        for column, header in zip(CELL_COLUMNS, headers, strict=True):
            if _text(ws[f"{column}{row + 1}"].value) != header:
                raise _unexpected(row + 1, column, header, ws[f"{column}{row + 1}"].value)
    for variable in NOISE_VARIABLES:
        column = "B" if variable.element == "Talking" else "C"
        if _text(ws[f"{column}{variable.row}"].value) != variable.element:
            found = ws[f"{column}{variable.row}"].value
            raise _unexpected(variable.row, column, variable.element, found)
    inputs = _prediction_cells(ws)
    task = movement = ""
    for sheet_row in ROWS:
        task = _text(ws[f"A{sheet_row.row}"].value) or task
        movement = _text(ws[f"B{sheet_row.row}"].value) or movement
        if sheet_row.table == NON_TRANSIENT:
            movement = ""
        found = (task, movement, _text(ws[f"C{sheet_row.row}"].value))
        expected = (sheet_row.task, sheet_row.movement, sheet_row.location)
        if found != expected:
            raise _unexpected(sheet_row.row, "A-C", " / ".join(expected), " / ".join(found))
        for column, evidence in zip(CELL_COLUMNS, sheet_row.cells, strict=True):
            asks = f"{column}{sheet_row.row}" in inputs
            if asks != (evidence is not None):
                what = "a prediction cell" if evidence is not None else "no input"
                raise _unexpected(sheet_row.row, column, what, "no input" if not asks else "input")
    return ws


def fill(ws: Any, dossier: Dossier) -> None:
    """Write the noise variables' performance and every prediction cell's colour."""
    for noise in dossier.noise:
        ws[f"{NOISE_COLUMN}{noise.variable.row}"] = noise.performance
    for cell in dossier.cells:
        if cell.colour is not None:
            ws[f"{cell.column}{cell.row.row}"] = cell.colour


def write_dossier(template: Path, dossier: Dossier, out: Path) -> Path:
    """The template with its prediction sheet filled from `dossier`, saved at `out` (written
    beside it first, then moved, so a failure leaves no half-written dossier)."""
    import openpyxl

    wb = openpyxl.load_workbook(template)
    try:
        fill(check_template(wb), dossier)
        partial = out.with_name(f".{out.name}.partial")
        wb.save(partial)
    finally:
        wb.close()
    partial.replace(out)
    return out


@dataclass(frozen=True, slots=True)
class Test:
    """A verification test the calculator selected: the prediction cell it checks (sheet row,
    column letter), the noise variable it is run under ("" none), on sheet row `line`."""

    line: int
    row: int
    column: str
    requirement: str
    noise: str


@dataclass(frozen=True, slots=True)
class Verification:
    """The calculator's verification sheet: its general requirements (sheet row, text), the
    tests it selected, the column answers go in, and any message it left instead."""

    general: tuple[tuple[int, str], ...]
    tests: tuple[Test, ...]
    value_column: str
    notes: tuple[str, ...]


def _header(ws: Any, row: int) -> dict[str, str]:
    return {_text(cell.value): cell.column_letter for cell in ws[row] if _text(cell.value) != ""}


def read_verification(path: Path) -> Verification:
    """The verification sheet of a workbook preprocessed by the calculator."""
    import openpyxl

    wb = openpyxl.load_workbook(path, data_only=True)
    try:
        if VERIFICATION not in wb.sheetnames:
            raise ConfigError(f"Euro NCAP's calculator wrote no sheet {VERIFICATION!r} in {path}")
        ws = wb[VERIFICATION]
        first = _header(ws, 1)
        if "Value" not in first:
            notes = tuple(_text(ws[f"A{r}"].value) for r in range(2, ws.max_row + 1))
            return Verification((), (), "", tuple(note for note in notes if note))
        general: list[tuple[int, str]] = []
        tests: list[Test] = []
        row = 2
        while row <= ws.max_row and _text(ws[f"A{row}"].value) != "Category":
            if _text(ws[f"{first['Scenario']}{row}"].value):
                general.append((row, _text(ws[f"{first['Scenario']}{row}"].value)))
            row += 1
        header = _header(ws, row) if row <= ws.max_row else {}
        for line in range(row + 1, ws.max_row + 1):
            point = TEST_POINT.fullmatch(_text(ws[f"{header['Test point']}{line}"].value))
            if point is None:
                continue
            requirement = _text(ws[f"{header['Requirement']}{line}"].value)
            noise = _text(ws[f"{header['Noise variable']}{line}"].value)
            column = CELL_COLUMNS[int(point[2]) - 4] if 4 <= int(point[2]) <= 6 else "?"
            tests.append(Test(line, int(point[1]), column, requirement, noise))
        return Verification(tuple(general), tuple(tests), first["Value"], ())
    finally:
        wb.close()


def write_answers(path: Path, column: str, answers: dict[int, str], out: Path) -> Path:
    """`path` with each answer (sheet row -> PASS, FAIL or N/A) in the verification sheet."""
    import openpyxl

    wb = openpyxl.load_workbook(path)
    try:
        ws = wb[VERIFICATION]
        for line, value in answers.items():
            ws[f"{column}{line}"] = value
        wb.save(out)
    finally:
        wb.close()
    return out


@dataclass(frozen=True, slots=True)
class Score:
    """Driver Monitoring as the calculator's report gives it (points None: not assessed)."""

    points: float | None
    max_points: float
    categories: tuple[tuple[str, float | None, float], ...]
    """(category, points, max) of each driver-monitoring category."""


def _number(value: Any) -> float | None:
    if isinstance(value, int | float) and math.isfinite(value):
        return float(value)
    return None


def _rows(ws: Any) -> list[dict[str, Any]]:
    """A score sheet's rows by header, its stage columns filled down."""
    header = [_text(c.value) for c in ws[1]]
    rows, last = [], {"Stage element": "", "Stage subelement": ""}
    for values in ws.iter_rows(min_row=2, values_only=True):
        row = dict(zip(header, values, strict=False))
        for name in last:
            last[name] = _text(row.get(name)) or last[name]
            row[name] = last[name]
        rows.append(row)
    return rows


def read_score(report: Path) -> Score:
    """Driver Monitoring's score and its categories from a compute-score report."""
    import openpyxl

    wb = openpyxl.load_workbook(report, data_only=True)
    try:
        dm = "Driver monitoring"
        tests = [r for r in _rows(wb["Test Scores"]) if r["Stage subelement"] == dm]
        if len(tests) != 1:
            raise ConfigError(f"{report}: no 'Driver monitoring' row in its 'Test Scores'")
        categories = tuple(
            (_text(r["Category"]), _number(r["Score"]), _number(r["Max score"]) or 0.0)
            for r in _rows(wb["Category Scores"])
            if r["Stage subelement"] == dm
        )
        total = _number(tests[0]["Max score"]) or 0.0
        return Score(_number(tests[0]["Score"]), total, categories)
    finally:
        wb.close()
