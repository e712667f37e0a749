"""The behaviours as the monitor runs them: the protocols' table, the events' rules, the
per-frame outputs, and docs/monitor.md's worked example, executed as written."""

from __future__ import annotations

import contextlib
import io
import re
import sys
import types

import pytest

from repo_paths import REPO
from roadgaze.config import MonitorConfig
from roadgaze.monitor import Monitor, initial_state, protocols, step
from roadgaze.monitor.behaviours import Clearing, DistractionState, Vats, VatsState
from roadgaze.monitor.context import Context
from roadgaze.monitor.events import Event, Publish, Raise
from roadgaze.monitor.protocols import ALL_RULES, TABLE, behaviours
from roadgaze.types import AlertKind, AlertLevel, Output, PoseSample

EXAMPLE_HEADING = "### Adding a behaviour: a worked example"


def sample(t_s: float, yaw_deg: float = 0.0) -> PoseSample:
    return PoseSample(
        t_s=t_s,
        frame=round(t_s * 15),
        face=True,
        yaw_raw_deg=yaw_deg,
        yaw_deg=yaw_deg,
        yaw_rate_dps=0.0,
        yaw_std_deg=1.0,
    )


def test_the_worked_example_in_the_docs_runs_and_prints_what_the_docs_say(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    text = (REPO / "docs" / "monitor.md").read_text(encoding="utf-8")
    section = text.split(EXAMPLE_HEADING, 1)[1].split("\n## ", 1)[0]
    code = re.findall(r"```python\n(.*?)```", section, re.DOTALL)
    printed = re.findall(r"```text\n(.*?)```", section, re.DOTALL)
    assert len(code) == 4 and len(printed) == 1
    module = types.ModuleType("docs_monitor_example")  # dataclasses look their module up
    monkeypatch.setitem(sys.modules, module.__name__, module)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        for block in code:
            exec(compile(block, "docs/monitor.md", "exec"), module.__dict__)
    assert out.getvalue() == printed[0]


@pytest.mark.parametrize(
    ("protocol", "expected"),
    [
        ("addw", ["Distraction", "Unavailable", "EyeClosure", "Drowsy", "Degraded"]),
        ("euroncap", ["Distraction", "Vats", "Unavailable", "EyeClosure", "Drowsy", "Degraded"]),
        ("both", ["Distraction", "Vats", "Unavailable", "EyeClosure", "Drowsy", "Degraded"]),
    ],
)
def test_the_table_runs_each_protocols_behaviours_in_order_clearing_last(
    protocol: str, expected: list[str]
) -> None:
    names = [type(b).__name__ for b in behaviours(protocol)]
    ncap = ["Unresponsive", "PhoneUse", "NonFunctional"] if protocol != "addw" else []
    assert names == [*expected, *ncap, "TemporaryFailure", "Support", "Support", "Clearing"]
    assert isinstance(behaviours(protocol)[-1], Clearing)


def test_every_rule_a_behaviour_is_configured_with_is_a_documented_rule() -> None:
    rules = {rule.key for rule in ALL_RULES}
    for _, behaviour in TABLE:
        for name in type(behaviour).__slots__:  # type: ignore[attr-defined]
            value = getattr(behaviour, name)
            if hasattr(value, "config_key"):
                assert value.key in rules, value.key
                assert hasattr(MonitorConfig(), value.config_key), value.config_key
    assert not hasattr(protocols, "rule_of")


def test_the_state_is_the_facts_and_one_slice_per_behaviour() -> None:
    config = MonitorConfig(protocol="addw", neutral_yaw_deg=0.0)
    state = initial_state(config)
    assert len(state.slices) == len(behaviours("addw"))
    assert state.slice(VatsState) is None and state.slice(DistractionState) == DistractionState()
    for t in range(5 * 15):  # 5 s looking 40 deg left at unknown speed: ADDW warns at 3.5 s
        state, alerts = step(config, state, sample(t / 15, 40.0), None)
        if alerts:
            assert [(a.kind, a.level, a.rule) for a in alerts] == [
                (AlertKind.LONG_DISTRACTION, AlertLevel.WARNING, "addw.distraction.above_50kmh")
            ]
            assert t / 15 == pytest.approx(3.5, abs=1 / 15)
    assert state.slice(DistractionState) == DistractionState(AlertLevel.WARNING)


class _Beacon:
    """A behaviour that publishes one output at every sample and raises nothing."""

    def initial(self) -> int:
        return 0

    def step(self, context: Context, state: int) -> tuple[int, tuple[Event, ...]]:
        rule = protocols.roadgaze.CLEAR
        return state + 1, (Publish("beacon", str(state), rule, "counting", context.t_s),)


def test_published_outputs_land_in_the_verdict_of_that_frame_only() -> None:
    config = MonitorConfig()
    *others, clearing = behaviours(config.protocol)
    monitor = Monitor(config, behaviours=(*others, _Beacon(), clearing))  # type: ignore[arg-type]
    assert monitor.verdict.outputs == ()
    monitor.update(sample(0.0))
    monitor.update(sample(0.1))
    beacons = tuple(o for o in monitor.verdict.outputs if o.name == "beacon")
    assert beacons == (
        Output("beacon", "1", "roadgaze.clear", "roadgaze's choice", "counting", 0.1),
    )
    # the support outputs come first (their behaviours run before the beacon)
    names = [o.name for o in monitor.verdict.outputs]
    assert names == ["support_forward", "support_lane", "beacon"]
    assert Monitor(config).verdict.outputs == ()


def test_a_behaviour_sees_the_events_raised_before_it_at_the_same_sample() -> None:
    seen: list[tuple[Event, ...]] = []

    class Spy:
        def initial(self) -> None:
            return None

        def step(self, context: Context, state: None) -> tuple[None, tuple[Event, ...]]:
            seen.append(context.events)
            return None, ()

    config = MonitorConfig(protocol="euroncap", neutral_yaw_deg=0.0)
    monitor = Monitor(config, behaviours=(*behaviours("euroncap")[:2], Spy()))  # type: ignore[arg-type]
    for t in range(int(3.2 * 15)):
        monitor.update(sample(t / 15, 40.0))
    raised = [e for events in seen for e in events if isinstance(e, Raise)]
    assert [(e.kind, e.rule.key) for e in raised] == [
        (AlertKind.LONG_DISTRACTION, "euroncap.long_distraction")
    ]
    assert isinstance(monitor.behaviours[1], Vats)
