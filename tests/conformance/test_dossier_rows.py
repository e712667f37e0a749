"""The sheet's table (`roadgaze.conformance.dossier_rows`): every key names a requirement that
the matrix really has, in both cabins; the rows sit in their tables; and, with the calculator
installed, the wording and the mandatory noise variables are the calculator's own."""

from __future__ import annotations

import pytest

from dossier_fakes import euroncap_scenarios
from roadgaze.conformance.dossier_rows import (
    GENERAL_REQUIREMENTS,
    NOISE_VARIABLES,
    ROWS,
    TABLES,
    key_for,
    row_at,
)
from roadgaze.conformance.model import Scenario, Segment
from roadgaze.synth.outfit import CONDITIONS


@pytest.mark.parametrize("cabin", ["lhd", "rhd"])
def test_every_key_names_a_requirement_of_the_matrix(cabin: str) -> None:
    known = {r.key for s in euroncap_scenarios(cabin) for r in s.requirements}
    keys = [key for row in ROWS for cell in row.cells if cell for key in cell]
    keys += [key for general in GENERAL_REQUIREMENTS for key in general.evidence]
    unknown = sorted({key_for(key, cabin) for key in keys} - known)
    assert keys and unknown == []


def test_rows_are_unique_in_sheet_order_and_inside_their_tables() -> None:
    numbers = [row.row for row in ROWS]
    assert numbers == sorted(set(numbers)) and len(numbers) == 47
    starts = sorted(TABLES.values())
    for row in ROWS:
        start = TABLES[row.table]
        end = next((s for s in starts if s > start), 10**6)
        assert start + 2 <= row.row < end, row
    assert row_at(70) is not None and row_at(70).task == "Microsleep"  # type: ignore[union-attr]
    assert row_at(32) is None
    assert [v.row for v in NOISE_VARIABLES] == list(range(2, 14))


def test_key_for_replaces_the_cabin_sides() -> None:
    assert key_for("side_{driver}_70.warns", "lhd") == "side_left_70.warns"
    assert key_for("mirror_{passenger}_70.quiet", "rhd") == "mirror_left_70.quiet"


def test_the_wording_and_the_mandatory_noise_variables_are_the_calculators() -> None:
    driver_monitoring = pytest.importorskip(
        "euroncap_rating_2026.safe_driving.driver_monitoring",
        reason="needs Euro NCAP's rating calculator (roadgaze[euroncap])",
    )
    texts = [general.text for general in GENERAL_REQUIREMENTS]
    assert texts == (
        driver_monitoring.GENERAL_REQUIREMENTS_PASS_FAIL
        + driver_monitoring.GENERAL_REQUIREMENTS_PASS_FAIL_NA
    )
    mandatory = [v.element for v in NOISE_VARIABLES if v.mandatory]
    assert mandatory == driver_monitoring.MANDATORY_FUNCTIONAL_ELEMENTS


def test_every_noise_variable_is_rendered_under_its_condition() -> None:
    """Each noise variable carries a variant rendering a scenario under one condition the
    renderer knows, named after it; the scenario is otherwise the same."""
    scenario = Scenario("lap_70", "a look", (Segment(1.0),), 70.0, (), conditions=("talking",))
    names = []
    for variable in NOISE_VARIABLES:
        assert variable.variant is not None, variable.element
        shown = variable.variant(scenario)
        condition = variable.variant.__name__
        assert condition in CONDITIONS and shown.conditions == ("talking", condition)
        assert shown.name == f"lap_70__{condition}" and shown.segments == scenario.segments
        names.append(condition)
    assert len(set(names)) == len(NOISE_VARIABLES) == 12
