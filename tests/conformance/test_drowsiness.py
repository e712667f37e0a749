"""The drowsiness scenarios: what they script (long blinks, yawns, a nod), the mouth track they
render, and once through the real service as a user runs it (`roadgaze conformance --protocol
euroncap --only ...`): drowsy at 70 km/h warns, alert at 70 and drowsy at 40 km/h do not."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from roadgaze.cli import main
from roadgaze.config import MonitorConfig
from roadgaze.conformance.clips import MOUTH_RAMP_S, mouth_track
from roadgaze.conformance.drowsiness import (
    LONG_BLINK_S,
    YAWN_OPENING,
    drowsiness_scenarios,
    drowsy_segments,
)
from roadgaze.conformance.matrix import scenario_matrix

pytestmark = pytest.mark.usefixtures("restore_logging")


def test_the_drowsy_drive_holds_long_blinks_two_yawns_and_a_nod() -> None:
    segments = drowsy_segments()
    closed = [s.duration_s for s in segments if s.openness == 0.0 and s.pitch_deg == 0.0]
    assert closed.count(LONG_BLINK_S) == 4  # and the nod's closure
    assert sum(1 for s in segments if s.mouth_open == YAWN_OPENING) == 2
    assert sum(1 for s in segments if s.pitch_deg < 0.0 and s.openness == 0.0) == 1
    names = [s.name for s in drowsiness_scenarios(MonitorConfig(protocol="euroncap"))]
    assert names == ["drowsy_70", "alert_70", "drowsy_40"]
    assert set(names) <= {s.name for s in scenario_matrix(MonitorConfig())}


def test_a_yawning_segment_eases_the_mouth_open_and_shut() -> None:
    (scenario, *_) = drowsiness_scenarios(MonitorConfig())
    starts = np.cumsum([0.0, *(s.duration_s for s in scenario.segments)])
    index = next(i for i, s in enumerate(scenario.segments) if s.mouth_open > 0.0)
    start, end = starts[index], starts[index + 1]
    t = np.array([start - 0.1, start + MOUTH_RAMP_S / 2, 0.5 * (start + end), end - 1e-3, end])
    # Cosine ease: half way up the ramp is half open; the middle is held; shut at the end.
    expected = [0.0, YAWN_OPENING / 2, YAWN_OPENING, 0.0, 0.0]
    assert mouth_track(scenario, t) == pytest.approx(expected, abs=1e-3)


@pytest.mark.slow
def test_drowsy_at_70_warns_alert_at_70_and_drowsy_at_40_do_not(tmp_path: Path) -> None:
    only = ["--only", "drowsy_70", "--only", "alert_70", "--only", "drowsy_40"]
    code = main(["conformance", "--protocol", "euroncap", *only, "--out", str(tmp_path)])
    results = json.loads((tmp_path / "conformance.json").read_text(encoding="utf-8"))
    outcomes = {r["requirement"]: r for r in results["outcomes"]}
    assert {k: outcomes[k]["result"] for k in outcomes} == {
        "drowsy_70.warns": "PASS",
        # forward and lane support from the warning to the end of the trip (row 68)
        "drowsy_70.support_forward": "PASS",
        "drowsy_70.support_lane": "PASS",
        "alert_70.quiet": "PASS",
        "drowsy_40.quiet": "PASS",
    }
    assert code == 0
    # The drowsy drive warns only once its level reached 7: at its nod (the third long blink
    # too) at the earliest, 9.2 s into it, and within the drowsy part (17.4 s).
    assert 9.0 <= outcomes["drowsy_70.warns"]["measured_s"] <= 17.4
