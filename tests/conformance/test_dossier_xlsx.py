"""The dossier in Euro NCAP's workbook (`roadgaze.conformance.dossier_xlsx`): the installed
calculator's template is where the table says, a template that is not is one line naming what
was found, and the filled sheet holds the dossier's values in the cells the calculator reads."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from dossier_fakes import FakeRunner, euroncap_scenarios, failing_under, outcomes_of
from roadgaze.conformance.dossier import judge
from roadgaze.conformance.dossier_xlsx import check_template, write_dossier
from roadgaze.errors import ConfigError

openpyxl = pytest.importorskip("openpyxl", reason="needs roadgaze[euroncap]")
integrity = pytest.importorskip(
    "euroncap_rating_2026.safe_driving.integrity",
    reason="needs Euro NCAP's rating calculator (roadgaze[euroncap])",
)
SHEET = "DE - DM pred."


def template() -> Path:
    """The calculator's own packaged Safe Driving template (never a copy in this repository)."""
    return Path(integrity.pristine_template_path())


def test_the_installed_template_is_where_the_table_says() -> None:
    wb = openpyxl.load_workbook(template())
    assert check_template(wb).title == SHEET


def _rename_sheet(wb: Any) -> None:
    wb[SHEET].title = "DM predictions"


def _move_a_row(wb: Any) -> None:
    wb[SHEET]["C18"] = "Radio"


def _move_a_table(wb: Any) -> None:
    wb[SHEET]["A15"] = "Distraction"


def _drop_a_dropdown(wb: Any) -> None:
    wb[SHEET].data_validations.dataValidation = [
        v for v in wb[SHEET].data_validations.dataValidation if "Green" not in str(v.formula1)
    ]


def _rename_a_noise_variable(wb: Any) -> None:
    wb[SHEET]["C8"] = "Mask"


@pytest.mark.parametrize(
    ("change", "found"),
    [
        (_rename_sheet, "has no sheet 'DE - DM pred.' (found Input parameters, "),
        (_move_a_row, "cell A-C18 holds 'Non-driving task / Owl / Radio', expected"),
        (_move_a_table, "cell A15 holds 'Distraction', expected 'Long distraction'"),
        (_drop_a_dropdown, "cell D17 holds 'no input', expected 'a prediction cell'"),
        (_rename_a_noise_variable, "cell C8 holds 'Mask', expected 'Face-mask'"),
    ],
)
def test_a_template_not_as_expected_is_one_line_naming_what_was_found(
    change: Callable[[Any], None], found: str
) -> None:
    wb = openpyxl.load_workbook(template())
    change(wb)
    with pytest.raises(ConfigError) as raised:
        check_template(wb)
    assert found in str(raised.value) and "\n" not in str(raised.value)


def test_the_filled_sheet_holds_the_dossiers_values(tmp_path: Path) -> None:
    scenarios = euroncap_scenarios()
    dark = failing_under("dark_sunglasses", scenario="side_left_70")
    runner = FakeRunner(failing=failing_under("night") | dark)
    dossier = judge(outcomes_of(scenarios, failed=("sleep_70.warns",)), scenarios, runner, "lhd")
    out = write_dossier(template(), dossier, tmp_path / "d.xlsx")
    ws = openpyxl.load_workbook(out)[SHEET]
    assert [ws[c].value for c in ("D17", "E17", "F17", "D69")] == ["Green"] * 3 + ["Red"]
    assert [ws[c].value for c in ("D70", "D71", "F72", "D26", "F68", "D68", "D69")] == [
        "Green",
        "Red",
        "Green",
        None,
        None,
        "Green",  # drowsiness
        "Red",  # non-fatigue impairment: nothing detects it
    ]
    # The mirror look failed at night (mandatory): its row 39 is not claimed, and night is
    # Functional for every cell left GREEN; under dark sunglasses (not mandatory) a look failed.
    assert [ws[c].value for c in ("E39", "F39")] == ["Red", "Red"]
    assert ws["D2"].value == "Functional" and ws["D4"].value == "Non Functional"
    assert ws["D3"].value == "Functional"  # clear sunglasses: every GREEN cell passed under them
    greens = sum(c.value == "Green" for row in ws["D17:F72"] for c in row)
    # 31 warnings (rows 17-25, 35-38, 47, 51-64, 68, 70 and 72's emergency function; sleep_70
    # failed), forward and lane support of rows 17-31, 35-47 (the driving-task looks included)
    # and 51-64, and the non-transient support of drowsiness, microsleep and sleep; less row
    # 39's two (the mirror look, failed at night)
    assert greens == sum(c.colour == "Green" for c in dossier.cells) == 31 + 42 * 2 + 3 - 2
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d.xlsx"]
