"""Every roadgaze alert of one vehicle, once, in order, checked (needs only eclipse-zenoh 1.x).

    python consume_alerts.py car-42 tcp/127.0.0.1:7447           # development: plain TCP
    python consume_alerts.py car-42 consumer-fcw/zenoh.json5       # `roadgaze security init` file

The advanced subscriber's history gives the daemon's last alerts when it joins (and when a daemon
appears later); recovery fetches, from the daemon's cache, alerts missed while a link was down.
Each alert is checked: size, JSON, schema, vehicle id, seq continuing its publisher's sequence
(a restarted daemon is a new publisher and starts at 0).
"""

import json
import queue
import sys
import time

import zenoh
from zenoh.ext import HistoryConfig, RecoveryConfig, declare_advanced_subscriber

MAX_BYTES = 64 * 1024
KINDS = {
    "long_distraction",
    "vats",
    "driver_unavailable",
    "microsleep",
    "sleep",
    "drowsy",
    "unresponsive",
    "degraded",
    "cleared",
}
LEVELS = {"info", "warning", "critical"}


def session_config(target: str) -> zenoh.Config:
    if target.endswith((".json5", ".json")):
        return zenoh.Config.from_file(target)
    settings = {
        "mode": "client",  # consumers are clients: two peers meet only if one listens
        "connect": {"endpoints": [target], "retry": {"period_init_ms": 250, "period_max_ms": 1000}},
        "scouting": {"multicast": {"enabled": False}},
    }
    return zenoh.Config.from_json5(json.dumps(settings))


def check(raw: bytes, vehicle_id: str) -> dict | str:
    """The alert, or why it is refused; never raises on hostile bytes."""
    if len(raw) > MAX_BYTES:
        return f"{len(raw)} bytes"
    try:
        alert = json.loads(raw.decode("utf-8"))
    except (RecursionError, UnicodeDecodeError, ValueError) as exc:
        return f"not JSON ({type(exc).__name__})"
    if not isinstance(alert, dict) or alert.get("schema") != "roadgaze.alert/3":
        return "not a roadgaze.alert/3"
    if alert.get("vehicle_id") != vehicle_id:
        return "another vehicle's id"
    if type(alert.get("seq")) is not int or alert["seq"] < 0:
        return "no valid seq"
    if alert.get("kind") not in KINDS or alert.get("level") not in LEVELS:
        return "unknown kind or level"
    if type(alert.get("t_s")) not in (int, float):
        return "no valid t_s"
    return alert


def main(vehicle_id: str, target: str, seconds: float = float("inf")) -> None:
    received: queue.Queue = queue.Queue(maxsize=10_000)

    def on_alert(sample: zenoh.Sample) -> None:  # O(1): Zenoh's thread only hands over
        source = str(sample.source_info.source_id) if sample.source_info else "plain"
        received.put((source, sample.payload.to_bytes()))

    next_seq: dict[str, int] = {}
    deadline = time.monotonic() + seconds
    with zenoh.open(session_config(target)) as session:
        subscriber = declare_advanced_subscriber(
            session,
            f"vehicle/{vehicle_id}/dms/alert",
            on_alert,
            history=HistoryConfig(detect_late_publishers=True, max_samples=100),
            recovery=RecoveryConfig(heartbeat=True),
        )
        misses = subscriber.sample_miss_listener(
            lambda miss: print(f"LOST {miss.nb} alerts (older than the cache)", file=sys.stderr)
        )
        try:
            while time.monotonic() < deadline:
                try:
                    source, raw = received.get(timeout=0.2)
                except queue.Empty:
                    continue
                alert = check(raw, vehicle_id)
                if isinstance(alert, str):
                    print(f"refused an alert: {alert}", file=sys.stderr)
                    continue
                expected = next_seq.get(source, alert["seq"])
                if alert["seq"] < expected:
                    continue  # already handled
                if alert["seq"] > expected:
                    print(f"GAP: {alert['seq'] - expected} alerts missing", file=sys.stderr)
                next_seq[source] = alert["seq"] + 1
                kind, level, seq, t_s = alert["kind"], alert["level"], alert["seq"], alert["t_s"]
                print(f"{kind} {level} seq={seq} t={t_s:.2f}s", flush=True)
        except KeyboardInterrupt:
            pass
        finally:
            misses.undeclare()
            subscriber.undeclare()


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2], *(float(arg) for arg in sys.argv[3:4]))
