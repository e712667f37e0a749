"""Issue 21's acceptance check on real faces (roadgaze.evaluation.held_out), a lean subset.

Pointing'04 development stills held as glances in a 15 fps clip after a frontal lead: looks
beyond 55 deg to either side and into the lap at 70 km/h warn 1.5-3.6 s after they start; a
1.5 s mirror glance and an 8 s lap glance at 10 km/h raise nothing. Two cases run as the
independent check does, with `replay --publish` and the speed put on the Zenoh bus by another
session (10 Hz, as a vehicle gateway would); the rest in process with a constant speed. Every
case on every subject: scripts/held-out-check.py. Skipped without the evaluation data.
"""

from __future__ import annotations

import json
import subprocess
import sys
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import zenoh

from repo_paths import POINTING04, child_env
from roadgaze.evaluation.held_out import (
    CASES,
    CaseResult,
    Stills,
    load_stills,
    result_of,
    run_case,
    with_support,
    write_clip,
)
from zenoh_helpers import endpoint, free_port, router, stop_process, wait_for

CASE = {case.name: case for case in CASES}
IN_PROCESS = [
    (3, "left60_4s_70"),  # reads 47 deg: the left mirror (a stay of 2 s counts from its start)
    (7, "right60_4s_70"),  # reads -52 deg: the right mirror
    (8, "lap30_4s_70"),  # reads 12 deg down: the neutral pitch learned from it until road
    (9, "right_mirror45_1.5s_70"),  # reads -60 deg: far_right, but only 1.5 s
]
"""(subject, case): looks that failed before the fixes (scripts/held-out-check.py), a mirror."""
OVER_THE_BUS = [(2, "left90_4s_70"), (1, "lap60_8s_10")]
"""A profile MediaPipe does not find (face lost: off road), and the lap below ADDW's speed."""


@pytest.fixture(scope="module")
def stills() -> dict[int, Stills]:
    if not (POINTING04 / "ground_truth.csv").is_file():
        pytest.skip(f"Pointing'04 development data not found under {POINTING04} (evaluation data)")
    return {s.subject: s for s in load_stills(POINTING04) if s.series == 1}


def test_the_verdict_of_a_case_from_its_alerts() -> None:
    """The acceptance rule itself: a warning 1.5-3.6 s after the look starts (times on the clip's
    timeline, the look at 4 s), or no alert but `cleared` on a look that must stay quiet."""
    someone = Stills(0, 1, {})
    zones, yaws = ["road"] * 120, [0.0] * 120

    def verdict(name: str, alerts: list[tuple[float, str, str]]) -> str:
        return result_of(someone, CASE[name], 4.0, alerts, zones, yaws).why_failed

    assert verdict("left75_4s_70", [(7.0, "long_distraction", ""), (8.0, "cleared", "")]) == ""
    assert verdict("left75_4s_70", [(7.7, "long_distraction", "")]) == "warned at 3.70 s"
    assert verdict("left75_4s_70", [(5.0, "long_distraction", "")]) == "warned at 1.00 s"
    assert verdict("left75_4s_70", [(6.0, "driver_unavailable", "")]) == "no warning"
    assert verdict("lap60_8s_10", [(9.0, "cleared", "")]) == ""
    assert verdict("left_mirror45_1.5s_70", [(5.0, "vats", "")]) == "raised vats"


def test_forward_support_must_go_from_normal_to_heightened_within_half_a_second() -> None:
    someone = Stills(0, 1, {})
    base = result_of(someone, CASE["left_mirror45_1.5s_70"], 4.0, [], ["road"] * 120, [0.0] * 120)

    def failed(levels: list[str]) -> str:
        return with_support(base, 4.0, levels).support_failed

    normal, heightened = "normal", "heightened"
    assert failed([normal] * 60 + [normal, heightened] + [heightened] * 10) == ""
    assert with_support(base, 4.0, [normal] * 61 + [heightened] * 2).support_s == 1 / 15
    assert failed([normal] * 60 + [normal] * 8 + [heightened]) == "support raised at 0.53 s"
    assert failed([normal] * 70) == "support not raised"
    assert failed([heightened] * 70) == "support heightened before the look"


def check(result: CaseResult, support: bool = True) -> None:
    """The case passed; with `support`, forward support was raised within 0.5 s too (measured
    in process: `run_case`)."""
    alerts = [(round(t, 2), kind) for t, kind, _ in result.alerts]
    print(f"subject {result.subject} {result.case.name}: warned at {result.warn_s}, {alerts}")
    assert result.passed, (
        f"{result.why_failed}: yaw {result.look_yaw_deg}, zones {set(result.look_zones)}, "
        f"alerts {result.alerts}"
    )
    if support:  # every look leaves the road
        assert not result.support_failed, result.support_failed


@pytest.mark.slow
@pytest.mark.parametrize(("subject", "name"), IN_PROCESS, ids=[f"{s}-{n}" for s, n in IN_PROCESS])
def test_a_held_still_warns_in_the_window_or_not_at_all(
    stills: dict[int, Stills], subject: int, name: str, tmp_path: Path
) -> None:
    check(run_case(stills[subject], CASE[name], folder=tmp_path))


class Bus:
    """A router on a free loopback port, a session putting `{"kmh": K}` on vehicle `held-out`'s
    speed key every 0.1 s (as a vehicle gateway would) and recording its alerts and states."""

    vehicle = "held-out"

    def __init__(self, session: zenoh.Session, port: int) -> None:
        self.session, self.port = session, port
        self.alerts: list[dict[str, Any]] = []
        self.states: list[dict[str, Any]] = []
        self._subscriber = session.declare_subscriber(
            f"vehicle/{self.vehicle}/dms/**", self._on_sample
        )

    def _on_sample(self, sample: zenoh.Sample) -> None:
        kind = str(sample.key_expr).rsplit("/", 1)[-1]
        if kind in ("alert", "state"):
            payload = json.loads(sample.payload.to_bytes())
            (self.alerts if kind == "alert" else self.states).append(payload)

    def provide(self, kmh: float, stop: threading.Event) -> None:
        while not stop.is_set():
            self.session.put(f"vehicle/{self.vehicle}/speed", json.dumps({"kmh": kmh}))
            stop.wait(0.1)


@pytest.fixture
def bus(request: pytest.FixtureRequest) -> Iterator[Bus]:
    port = free_port()
    stop = threading.Event()
    with router(port) as session:
        hub = Bus(session, port)
        provider = threading.Thread(target=hub.provide, args=(request.param, stop), daemon=True)
        provider.start()
        try:
            yield hub
        finally:
            stop.set()
            provider.join(timeout=5.0)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("subject", "name", "bus"),
    [(s, n, CASE[n].speed_kmh) for s, n in OVER_THE_BUS],
    ids=[f"{s}-{n}" for s, n in OVER_THE_BUS],
    indirect=["bus"],
)
def test_replay_publish_with_the_speed_on_the_bus(
    stills: dict[int, Stills], subject: int, name: str, bus: Bus, tmp_path: Path
) -> None:
    case = CASE[name]
    clip = tmp_path / "clip.avi"
    look_t_s = write_clip(clip, stills[subject], case)
    out = tmp_path / "frames.jsonl"
    args = ["replay", str(clip), "--publish", "--vehicle-id", bus.vehicle]
    args += ["--zenoh-connect", endpoint(bus.port), "--no-progress", "--out", str(out)]
    process = subprocess.Popen(
        [sys.executable, "-m", "roadgaze", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=child_env(GLOG_minloglevel="2"),
    )
    try:
        _, stderr = process.communicate(timeout=120)
    finally:
        stop_process(process)
    assert process.returncode == 0, stderr[-2000:]
    assert wait_for(lambda: any(s["status"] == "stopped" for s in bus.states), timeout_s=5.0)
    final = next(s for s in bus.states if s["status"] == "stopped")
    assert final["monitor"]["speed_kmh"] == case.speed_kmh
    records = [json.loads(line) for line in out.read_text().splitlines()]
    alerts = [(a["t_s"], a["kind"], a["reason"]) for a in bus.alerts]
    zones, yaws = [r["zone"] for r in records], [r["yaw_deg"] for r in records]
    check(result_of(stills[subject], case, look_t_s, alerts, zones, yaws), support=False)
