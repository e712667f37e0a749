"""The dossier judged from outcomes: GREEN only where every requirement behind a cell passed,
noise variables Functional only where every GREEN cell passed again under them, the general
requirements answered with their basis (`roadgaze.conformance.dossier`)."""

from __future__ import annotations

from dataclasses import replace

import pytest

from dossier_fakes import (
    MANDATORY,
    NOTICES,
    FakeRunner,
    euroncap_scenarios,
    failing_everything_under,
    failing_under,
    outcomes_of,
)
from roadgaze.conformance.dossier import (
    GREEN,
    RED,
    judge,
    judge_cells,
    outcomes_by_key,
    with_gates_met,
)
from roadgaze.conformance.model import Outcome
from roadgaze.conformance.notices import notice_key

SCENARIOS = euroncap_scenarios()


@pytest.mark.parametrize(
    ("failed", "not_applicable", "colour", "why"),
    [
        ((), (), GREEN, "PASS: side_left_70.warns 2.00 s"),
        (("side_left_70.warns",), (), RED, "FAIL: side_left_70.warns 2.00 s (FAIL)"),
        ((), ("side_left_70.warns",), RED, "FAIL: side_left_70.warns 2.00 s (N/A)"),
    ],
)
def test_a_cell_is_green_only_when_its_requirement_passed(
    failed: tuple[str, ...], not_applicable: tuple[str, ...], colour: str, why: str
) -> None:
    results = outcomes_by_key(outcomes_of(SCENARIOS, failed, not_applicable))
    cells = {(c.row.row, c.column): c for c in judge_cells(results, "lhd")}
    driver_window = cells[(17, "D")]
    assert (driver_window.colour, driver_window.why) == (colour, why)
    assert driver_window.keys == ("side_left_70.warns",)


def test_every_requirement_of_a_cell_must_pass_and_be_run() -> None:
    results = outcomes_by_key(outcomes_of(SCENARIOS, failed=("vats_below_70.quiet",)))
    vats = {(c.row.row, c.column): c for c in judge_cells(results, "lhd")}[(35, "D")]
    assert vats.colour == RED and "vats_below_70.quiet" in vats.why
    not_run = [o for o in outcomes_of(SCENARIOS) if o.scenario != "sleep_70"]
    sleep = {(c.row.row, c.column): c for c in judge_cells(outcomes_by_key(not_run), "lhd")}
    assert (sleep[(71, "D")].colour, sleep[(71, "D")].why) == (RED, "not run: sleep_70.warns")


def test_cells_without_a_scenario_are_red_and_the_sheets_gaps_are_left_out() -> None:
    cells = {(c.row.row, c.column): c for c in judge_cells(outcomes_by_key([]), "lhd")}
    assert all(c.colour in (RED, None) for c in cells.values())
    assert (cells[(69, "D")].colour, cells[(69, "D")].why) == (RED, "no scenario measures it yet")
    assert (cells[(19, "D")].colour, cells[(19, "D")].why) == (
        RED,
        "not run: owl_passenger_footwell_70.warns",
    )
    assert cells[(26, "D")].colour is None  # a mirror glance earns no warning points
    assert cells[(72, "D")].colour is None and cells[(68, "F")].colour is None
    assert len(cells) == 47 * 3


def test_a_right_hand_drive_cabin_swaps_the_driver_and_passenger_sides() -> None:
    scenarios = euroncap_scenarios("rhd")
    results = outcomes_by_key(outcomes_of(scenarios, failed=("side_left_70.warns",)))
    cells = {(c.row.row, c.column): c for c in judge_cells(results, "rhd")}
    assert cells[(17, "D")].keys == ("side_right_70.warns",) and cells[(17, "D")].colour == GREEN
    assert cells[(21, "D")].keys == ("side_left_70.warns",) and cells[(21, "D")].colour == RED


def test_noise_variables_are_functional_only_when_every_green_cell_passes_under_them() -> None:
    runner = FakeRunner(failing=failing_under("hat"))
    dossier = judge(outcomes_of(SCENARIOS), SCENARIOS, runner, "lhd")
    sunglasses = dossier.noise_of("Dark sunglasses")
    assert sunglasses is not None and sunglasses.performance == "Functional"
    green = {key.split(".")[0] for c in dossier.cells if c.colour == GREEN for key in c.keys}
    ran = [name for name in runner.calls if name.endswith("__dark_sunglasses")]
    assert {name.removesuffix("__dark_sunglasses") for name in ran} == green
    hat = dossier.noise_of("Hat")
    assert hat is not None and hat.performance == "Non Functional"
    assert [name for name in runner.calls if name.endswith("__hat")] == ["mirror_left_70__hat"]
    assert all(n.variable.variant is not None for n in dossier.noise)


def test_a_cell_failing_under_a_mandatory_noise_variable_is_not_claimed() -> None:
    # The mirror look fails at night: its cells turn RED, saying why, and night stays
    # Functional for every cell still GREEN (each scenario was run under it, not just the first).
    runner = FakeRunner(failing=failing_under("night"))
    plain = judge_cells(outcomes_by_key(outcomes_of(SCENARIOS)), "lhd")
    dossier = judge(outcomes_of(SCENARIOS), SCENARIOS, runner, "lhd")
    turned = [(a, b) for a, b in zip(plain, dossier.cells, strict=True) if a.colour != b.colour]
    assert turned and all(b.colour == RED for _, b in turned)
    assert {k.split(".")[0] for _, b in turned for k in b.keys} >= {"mirror_left_70"}
    assert all(
        "RED under Daytime - Night-time (mandatory): FAIL: mirror_left_70." in b.why
        for _, b in turned
    )
    assert all(a.why in b.why for a, b in turned)  # the plain run's PASS is kept in the why
    night = dossier.noise_of("Daytime - Night-time")
    assert night is not None and night.performance == "Functional"
    assert night.why.startswith("PASS: ")
    ran = [n.removesuffix("__night") for n in runner.calls if n.endswith("__night")]
    assert set(ran) == {k.split(".")[0] for c in plain if c.colour == GREEN for k in c.keys}
    assert len(ran) == len(set(ran))  # run once: the noise table reads the same outcomes
    # Failing everything at night leaves no GREEN cell: night is not shown functional.
    everything = FakeRunner(failing=failing_everything_under("night"))
    dark = judge(outcomes_of(SCENARIOS), SCENARIOS, everything, "lhd")
    assert not any(c.colour == GREEN for c in dark.cells)
    night = dark.noise_of("Daytime - Night-time")
    assert night is not None and night.why == "no GREEN cell to show it on"


def test_a_noise_variable_stops_at_the_first_scenario_failing_under_it() -> None:
    runner = FakeRunner(failing={"mirror_left_70__dark_sunglasses"})
    dossier = judge(outcomes_of(SCENARIOS), SCENARIOS, runner, "lhd")
    sunglasses = dossier.noise_of("Dark sunglasses")
    assert sunglasses is not None and not sunglasses.functional
    failed = "mirror_left_70__dark_sunglasses: FAIL: mirror_left_70.support_forward"
    assert sunglasses.why.startswith(failed)
    ran = [name for name in runner.calls if name.endswith("__dark_sunglasses")]
    assert ran == ["mirror_left_70__dark_sunglasses"]  # the shortest drive goes first


def test_general_requirements_answer_pass_fail_or_na_with_their_basis() -> None:
    outcomes = outcomes_of(SCENARIOS, failed=("lap_70.warns", notice_key("hat")))
    cap_fails = failing_under("cap", scenario="side_left_70")
    runner = FakeRunner(failing=cap_fails | failing_under("hat"))
    dossier = judge(outcomes, SCENARIOS, runner, "lhd")
    answers = {g.requirement.text: g for g in dossier.general}
    assert answers["Default ON at the start of every journey"].value == "FAIL"
    assert answers["Continuous monitoring of the driver state"].value == "PASS"
    assisted = next(g for text, g in answers.items() if text.startswith("Assisted Driving"))
    assert assisted.value == "PASS" and assisted.why.startswith("taken as met")
    sunglasses = next(g for text, g in answers.items() if text.endswith("dark sunglasses"))
    assert sunglasses.value == "N/A"  # dark sunglasses shown functional: nothing to inform of
    cap = next(g for text, g in answers.items() if text.endswith("wears a cap"))
    assert cap.value == "PASS"  # the cap not shown functional: its notice was measured
    assert cap.why.startswith("the service raised `non_functional` within 10 s")
    # No notice under a hat: Non Functional, the hat would hold the score at 0, so the cells
    # failing under it (the mirror look) are not claimed and the hat is shown Functional.
    hat = next(g for text, g in answers.items() if text.endswith("wears a hat"))
    assert hat.value == "N/A"
    mirror = [c for c in dossier.cells if any(k.startswith("mirror_left_70.") for k in c.keys)]
    assert mirror and all(c.colour == RED for c in mirror)
    assert all("RED under Hat (no notice given): FAIL: mirror_left_70." in c.why for c in mirror)
    # With nothing left to claim under the hat, it is Non Functional and its notice FAILs.
    everything = FakeRunner(failing=failing_everything_under("hat"))
    answers = {g.requirement.text: g for g in judge(outcomes, SCENARIOS, everything, "lhd").general}
    hat = next(g for text, g in answers.items() if text.endswith("wears a hat"))
    assert hat.value == "FAIL" and hat.why.startswith("FAIL: notice_hat_70.told")


def test_a_notice_not_run_does_not_hold_the_cells_under_its_condition() -> None:
    # Without the hat's notice scenario (--only), nothing says whether a notice is given: the
    # mirror look failing under the hat keeps its cells, and the hat is Non Functional.
    outcomes = [o for o in outcomes_of(SCENARIOS) if o.scenario != "notice_hat_70"]
    dossier = judge(outcomes, SCENARIOS, FakeRunner(failing=failing_under("hat")), "lhd")
    mirror = [c for c in dossier.cells if any(k.startswith("mirror_left_70.") for k in c.keys)]
    assert mirror and all(c.colour == GREEN for c in mirror)
    hat = dossier.noise_of("Hat")
    assert hat is not None and hat.performance == "Non Functional"
    told = {g.requirement.label: g for g in dossier.general}["notice: hat"]
    assert told.value == "FAIL" and told.why.startswith("not run: notice_hat_70.told")


def test_the_activation_speed_passes_only_when_the_rules_are_active_at_every_speed() -> None:
    label = "speed activation of distraction, microsleep, sleep, unresponsive"
    # Configured active from 0 km/h, the 8 s lap look at 10 km/h warns: any figure is met.
    slow = [o for o in outcomes_of(SCENARIOS) if o.requirement.key != "lap_8s_10.quiet"]
    quiet = next(o for o in outcomes_of(SCENARIOS) if o.requirement.key == "lap_8s_10.quiet")
    warned = replace(quiet, measured_s=3.2, passed=False)

    def answer(outcomes: list[Outcome], min_speed_kmh: float | None) -> tuple[str, str]:
        dossier = judge(outcomes, SCENARIOS, FakeRunner(), "lhd", min_speed_kmh)
        verdict = {g.requirement.label: g for g in dossier.general}[label]
        return verdict.value, verdict.why

    value, why = answer([*slow, warned], 0.0)
    assert value == "PASS" and why.startswith("min_speed_kmh 0: the rules are active at every")
    assert why.endswith("(lap_8s_10 warned 3.20 s into its look)")
    # The default 20 km/h, an unknown setting, or a slow look that stayed quiet: not shown.
    for outcomes, min_speed in (
        ([*slow, warned], 20.0),
        ([*slow, warned], None),
        ([*slow, quiet], 0.0),
    ):
        value, why = answer(outcomes, min_speed)
        assert value == "FAIL" and why.startswith("the protocol's activation speed was not read")


def test_the_gates_name_what_holds_the_score_and_can_be_taken_as_met() -> None:
    runner = FakeRunner(failing=failing_everything_under(*MANDATORY) | failing_under(*NOTICES))
    dossier = judge(outcomes_of(SCENARIOS), SCENARIOS, runner, "lhd")
    gates = dossier.gates()
    assert gates[0] == (
        "mandatory noise variables not shown functional: Daytime - Night-time, Clear "
        "sunglasses, Short facial hair, Long facial hair, Face-mask"
    )
    assert gates[1] == (
        "1 general requirement not met: speed activation of distraction, microsleep, sleep, "
        "unresponsive"
    )
    assert "impairment" not in gates[1]  # drowsiness' scenarios passed: its activation is shown
    opened = with_gates_met(dossier)
    assert opened.gates() == [] and opened.cells == dossier.cells
    cap = opened.noise_of("Cap")
    assert cap is not None and not cap.functional  # only the mandatory ones are taken as met
