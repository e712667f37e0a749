"""Conformance outcomes without running the service, for the dossier's tests: every requirement
of the real scenario matrix, passed or failed as a test says, and a runner that records what it
was asked to run again."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import replace

from roadgaze.config import Config
from roadgaze.conformance.matrix import scenario_matrix
from roadgaze.conformance.model import Outcome, Scenario


def euroncap_scenarios(cabin: str = "lhd") -> list[Scenario]:
    """The matrix under `--protocol euroncap` in `cabin`."""
    config = Config()
    monitor = config.monitor.model_dump() | {"protocol": "euroncap", "cabin": cabin}
    return scenario_matrix(type(config.monitor).model_validate(monitor))


def outcomes_of(
    scenarios: Iterable[Scenario], failed: Iterable[str] = (), not_applicable: Iterable[str] = ()
) -> list[Outcome]:
    """Every requirement of `scenarios` passed, but for the keys in `failed` (FAIL) and in
    `not_applicable` (N/A)."""
    failed, not_applicable = set(failed), set(not_applicable)
    outcomes = []
    for scenario in scenarios:
        for requirement in scenario.requirements:
            if requirement.key in not_applicable:
                requirement = replace(requirement, applies=False)
            measured = None if requirement.window_s is None else requirement.window_s[0] + 0.5
            passed = requirement.key not in failed
            outcomes.append(Outcome(scenario.name, requirement, measured, passed))
    return outcomes


class FakeRunner:
    """Answers every scenario run again as passing, but those named in `failing` (every one of
    their requirements FAIL); `calls` lists the names asked for, in order."""

    def __init__(self, failing: Iterable[str] = ()) -> None:
        self.failing = set(failing)
        self.calls: list[str] = []

    def __call__(self, scenarios: Sequence[Scenario]) -> list[Outcome]:
        self.calls += [s.name for s in scenarios]
        failed = [r.key for s in scenarios if s.name in self.failing for r in s.requirements]
        return outcomes_of(scenarios, failed)


def failing_under(*conditions: str, scenario: str = "mirror_left_70") -> set[str]:
    """`scenario` (the shortest GREEN drive, run first) under each of `conditions`: a
    `FakeRunner` failing these shows those noise variables not functional."""
    return {f"{scenario}__{condition}" for condition in conditions}


def failing_everything_under(*conditions: str) -> set[str]:
    """Every scenario of the euroncap matrix under each of `conditions`: a `FakeRunner` failing
    these leaves no GREEN cell standing under a mandatory one (so it is not shown functional)."""
    return {f"{s.name}__{condition}" for s in euroncap_scenarios() for condition in conditions}


MANDATORY = ("night", "clear_sunglasses", "stubble", "beard", "mask")
"""The conditions of the five mandatory noise variables."""
NOTICES = ("hand_at_12", "cap", "hat", "fringe", "eyelash_makeup")
"""The conditions whose noise variables ask for a non-functional notice (dark sunglasses aside)."""
