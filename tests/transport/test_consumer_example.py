"""The consumer example of docs/zenoh.md (docs/examples/consume_alerts.py) works as shown."""

from __future__ import annotations

import signal
import subprocess
import sys

import zenoh

from fakes import alert_message
from repo_paths import REPO
from roadgaze.config import ZenohConfig
from roadgaze.transport import Keys, ZenohLink
from zenoh_helpers import LineReader, endpoint, free_port, router, stop_process, wait_for

EXAMPLE = REPO / "docs" / "examples" / "consume_alerts.py"


def test_the_example_gets_history_then_live_alerts_and_refuses_forgeries() -> None:
    port = free_port()
    config = ZenohConfig(vehicle_id="car-42", connect=[endpoint(port)])
    with router(port) as bus, ZenohLink(config, Keys.from_config(config)) as link:
        assert wait_for(lambda: link.status().connected, timeout_s=15.0)
        for seq in range(3):  # before the consumer exists: it gets them from the cache
            link.publish_alert(alert_message(seq, "car-42"))
        process = subprocess.Popen(
            [sys.executable, str(EXAMPLE), "car-42", endpoint(port), "5"],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        )  # fmt: skip
        try:
            reader = LineReader(process)
            lines = [reader.next(20.0) for _ in range(3)]
            block = zenoh.CongestionControl.BLOCK  # the default (DROP) may lose them under load
            bus.put(
                link.keys.alert, alert_message(7, "car-9").to_json_bytes(), congestion_control=block
            )
            bus.put(link.keys.alert, b"[" * 50_000, congestion_control=block)
            link.publish_alert(alert_message(3, "car-42"))
            lines.append(reader.next(10.0))
            _, stderr = process.communicate(timeout=30)
        finally:
            stop_process(process)
    assert lines == [f"long_distraction warning seq={seq} t=7.00s" for seq in range(4)]
    assert stderr.count("refused an alert") == 2 and "Traceback" not in stderr
    assert "```python\n" + EXAMPLE.read_text() in (REPO / "docs" / "zenoh.md").read_text()


def test_the_example_started_before_the_router_waits_then_reports_gaps_and_intruders() -> None:
    """Issue 27: it died with `zenoh.ZError: Unable to connect`; issue 24: gaps and second
    publishers were not reported, totals never printed; issue 34: a second publisher's alerts
    were dropped (the forger may be the first): now both are shown, flagged."""
    port = free_port()
    process = subprocess.Popen(
        [sys.executable, str(EXAMPLE), "car-42", endpoint(port), "12"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        errors = LineReader(process, process.stderr)
        errors.until("waiting for a router or daemon", 20.0)
        config = ZenohConfig(vehicle_id="car-42", connect=[endpoint(port)])
        with (
            router(port),
            ZenohLink(config, Keys.from_config(config)) as link,
            ZenohLink(config, Keys.from_config(config)) as intruder,
        ):
            assert wait_for(lambda: link.status().connected, timeout_s=15.0)
            assert wait_for(lambda: intruder.status().connected, timeout_s=15.0)
            reader = LineReader(process)
            link.publish_alert(alert_message(2, "car-42"))  # #0 and #1 never reached it
            assert reader.next(20.0) == "long_distraction warning seq=2 t=7.00s"
            intruder.publish_alert(alert_message(100, "car-42"))
            said = errors.until("SUSPICIOUS: 2 publishers of car-42's alerts", 10.0)
            flagged = reader.next(10.0) or ""  # shown, never dropped: either may be the forger
            assert flagged.startswith("long_distraction warning seq=100 t=7.00s SUSPICIOUS: ")
            assert "publisher 2 of 2 of car-42" in flagged
            link.publish_alert(alert_message(3, "car-42"))
            own = reader.next(10.0) or ""
            assert own.startswith("long_distraction warning seq=3 t=7.00s SUSPICIOUS: publisher 1")
            process.send_signal(signal.SIGINT)
            said += errors.until("refused (plain puts)", 20.0)
            process.wait(timeout=20)
    finally:
        stop_process(process)
    assert any(line.startswith("MISSED alerts #0-#1 of car-42 (2)") for line in said)
    assert not any("Traceback" in line for line in said)
    assert said[-1] == (
        "2 alerts, 1 flagged (a second publisher), 2 missed, 0 rejected, 0 refused (plain puts)"
    )
