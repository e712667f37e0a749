"""Runs the suite: each scenario rendered, replayed through the real service, judged.

Each drive goes through the same loop as `roadgaze replay` (`Pipeline`, MediaPipe in VIDEO mode,
a fresh landmarker per drive) with the vehicle speed read from the drive's speed track the way
`replay` and `batch` read it (the run built by `roadgaze.pipeline.build_run`), and the service
told the scenario's camera mounting. Every alert is kept; each requirement is judged on them.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from roadgaze.capture import FrameSource
from roadgaze.config import Config
from roadgaze.conformance.clips import CLIP_SUFFIX, RenderedSource, ScenarioRenderer
from roadgaze.conformance.model import Outcome, Requirement, Scenario, judge
from roadgaze.conformance.support import SUPPORT_OUTPUTS, SupportLog, judge_support
from roadgaze.types import Alert, Frame, FrameRecord

log = logging.getLogger(__name__)

Alerts = list[tuple[str, str, float]]
"""(kind, level, t_s) of every alert of a drive, in order, with the changes of its support
(output, level, t_s)."""


class AlertLog:
    """A sink keeping every alert of the drive, and each change of its forward and lane support
    (as (`support_forward`, level, t_s): roadgaze.conformance.support)."""

    def __init__(self) -> None:
        self.alerts: Alerts = []
        self.support = SupportLog(self.alerts)  # one list, in the order they came

    def on_record(self, record: FrameRecord, frame: Frame) -> None:
        self.support.on_record(record)
        for alert in record.alerts:
            self.on_alert(alert)

    def on_alert(self, alert: Alert) -> None:
        self.alerts.append((alert.kind.value, alert.level.value, alert.t_s))

    def close(self) -> None:
        return None


def scenario_config(config: Config, scenario: Scenario) -> Config:
    """`config` with the service told where the scenario's camera sits."""
    monitor = config.monitor.model_dump()
    monitor["camera_mounting"] = scenario.mounting
    return config.model_copy(update={"monitor": type(config.monitor).model_validate(monitor)})


def replay_drive(source: FrameSource, track: Path | None, config: Config) -> Alerts:
    """Every alert the service raises on `source`, the speed from `track` (None: unknown)."""
    from roadgaze.pipeline import RunOptions, build_run

    sink = AlertLog()
    options = RunOptions(source.info.name, command="conformance", speed_track=track, quiet=True)
    with build_run(config, options, source=source, sinks=(sink,)) as run:
        run.run()
    return sink.alerts


def clock_start(scenario: Scenario, requirement: Requirement, alerts: Alerts) -> float | None:
    """When the requirement's clock starts: at its labelled segment, or at the first alert it
    follows (`from_alert`; None: that alert never came)."""
    if requirement.from_alert:
        warned = (t_s for kind, _, t_s in alerts if kind == requirement.from_alert)
        return min(warned, default=None)
    return scenario.start_of(requirement.from_label)


def outcomes_of(scenario: Scenario, alerts: Alerts) -> list[Outcome]:
    """Each requirement of `scenario` judged on the drive's alerts."""
    shown = tuple(
        f"{kind}:{level}@{t_s:.2f}" for kind, level, t_s in alerts if kind not in SUPPORT_OUTPUTS
    )
    results = []
    for requirement in scenario.requirements:
        start_s = clock_start(scenario, requirement, alerts)
        if start_s is None:
            measured, passed = None, False  # the warning it follows never came
        elif requirement.held_until:
            until = requirement.held_until
            until_s = scenario.duration_s if until == "end" else scenario.start_of(until)
            from_normal = not requirement.from_alert
            measured, passed = judge_support(requirement, start_s, until_s, alerts, from_normal)
        else:
            measured, passed = judge(requirement, start_s, alerts)
        results.append(Outcome(scenario.name, requirement, measured, passed, shown))
    return results


@dataclass(frozen=True, slots=True)
class SuiteRun:
    """The outcomes of a run, in scenario order, and how long it took."""

    outcomes: tuple[Outcome, ...]
    scenarios: int
    wall_s: float

    @property
    def failed(self) -> tuple[Outcome, ...]:
        """The requirements that apply and failed (one of another protocol is N/A, not FAIL)."""
        return tuple(outcome for outcome in self.outcomes if outcome.result == "FAIL")


def run_suite(
    scenarios: Sequence[Scenario],
    config: Config,
    clips_dir: Path,
    renderer: ScenarioRenderer,
    on_scenario: Callable[[Scenario, list[Outcome]], None] | None = None,
    save_clips: bool = False,
) -> SuiteRun:
    """Render, replay and judge every scenario; each one's truth and speed track go to
    `clips_dir`, with its video too when `save_clips`."""
    started = time.perf_counter()
    outcomes: list[Outcome] = []
    for scenario in scenarios:
        track = renderer.write_side_files(scenario, clips_dir)
        clip = clips_dir / f"{scenario.name}{CLIP_SUFFIX}" if save_clips else None
        source = RenderedSource(renderer, scenario, clip)
        alerts = replay_drive(source, track, scenario_config(config, scenario))
        results = outcomes_of(scenario, alerts)
        outcomes.extend(results)
        if on_scenario is not None:
            on_scenario(scenario, results)
    return SuiteRun(tuple(outcomes), len(scenarios), time.perf_counter() - started)
