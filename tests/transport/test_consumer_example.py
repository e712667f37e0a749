"""The consumer example of docs/zenoh.md (docs/examples/consume_alerts.py) works as shown."""

from __future__ import annotations

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
