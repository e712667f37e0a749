"""Every roadgaze alert of one vehicle, once, in order, checked (needs only eclipse-zenoh 1.x).

    python consume_alerts.py car-42 tcp/127.0.0.1:7447           # development: plain TCP
    python consume_alerts.py car-42 consumer-fcw/zenoh.json5       # `roadgaze security init` file

It may start before the router or the daemon (an FCW boots first): it waits for them. The
advanced subscriber's history gives the daemon's last alerts when it joins (and when a daemon
appears later); recovery fetches, from the daemon's cache, alerts missed while a link was down.
Each alert is checked: size, JSON, schema, vehicle id, seq continuing its publisher's sequence
(a restarted daemon is a new publisher and starts at 0). Missing numbers are reported as a
range (`MISSED #0-#2`); alerts from a second publisher of this vehicle (another Zenoh session,
or a plain put) are flagged every time and not used; the totals are printed at exit.
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


def open_when_reachable(target: str, deadline: float) -> zenoh.Session | None:
    """A client cannot open before its router answers: try again every second."""
    config, waiting = session_config(target), False
    while True:
        try:
            return zenoh.open(config)
        except zenoh.ZError as exc:
            if time.monotonic() + 1.0 > deadline:
                print(f"no router at {target}: {str(exc).split(' at /')[0]}", file=sys.stderr)
                return None
            if not waiting:
                print(f"waiting for the router at {target}", file=sys.stderr, flush=True)
                waiting = True
            time.sleep(1.0)


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
        source = str(sample.source_info.source_id) if sample.source_info else None
        received.put(("alert", source, sample.payload.to_bytes()))

    def on_alive(sample: zenoh.Sample) -> None:  # the daemon went: its successor is accepted
        if sample.kind == zenoh.SampleKind.DELETE:
            received.put(("left", None, b""))

    next_seq: dict[str, int] = {}
    totals = {"alerts": 0, "missed": 0, "rejected": 0, "foreign": 0}
    publisher = None  # the vehicle's daemon: the first advanced publisher seen
    deadline = time.monotonic() + seconds
    session = open_when_reachable(target, deadline)
    if session is None:
        return
    with session:
        prefix = f"vehicle/{vehicle_id}/dms"
        alive = session.liveliness().declare_subscriber(f"{prefix}/alive", on_alive)
        subscriber = declare_advanced_subscriber(
            session,
            f"{prefix}/alert",
            on_alert,
            history=HistoryConfig(detect_late_publishers=True, max_samples=100),
            recovery=RecoveryConfig(heartbeat=True),
        )
        misses = subscriber.sample_miss_listener(
            lambda miss: received.put(("miss", str(miss.source), miss.nb))
        )
        try:
            while time.monotonic() < deadline:
                try:
                    what, source, data = received.get(timeout=0.2)
                except queue.Empty:
                    continue
                if what == "left":
                    publisher = None
                    continue
                if what == "miss":  # the range is printed with the next alert
                    print(f"zenoh: {data} alerts missed", file=sys.stderr)
                    continue
                alert = check(data, vehicle_id)
                if isinstance(alert, str):
                    totals["rejected"] += 1
                    print(f"refused an alert: {alert}", file=sys.stderr)
                    continue
                publisher = publisher or source
                if source is None or source != publisher:
                    totals["foreign"] += 1
                    print(f"SUSPICIOUS: alert #{alert['seq']} from a second publisher "
                          f"({source or 'a plain put'}); not used", file=sys.stderr)  # fmt: skip
                    continue
                expected = next_seq.get(source, 0)
                if alert["seq"] < expected:
                    continue  # already handled
                if alert["seq"] > expected:  # never received: older than the daemon's cache
                    totals["missed"] += alert["seq"] - expected
                    print(f"MISSED #{expected}-#{alert['seq'] - 1}", file=sys.stderr)
                next_seq[source] = alert["seq"] + 1
                totals["alerts"] += 1
                kind, level, seq, t_s = alert["kind"], alert["level"], alert["seq"], alert["t_s"]
                print(f"{kind} {level} seq={seq} t={t_s:.2f}s", flush=True)
        except KeyboardInterrupt:
            pass
        finally:
            misses.undeclare()
            subscriber.undeclare()
            alive.undeclare()
            print(", ".join(f"{count} {name}" for name, count in totals.items()), file=sys.stderr)


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2], *(float(arg) for arg in sys.argv[3:4]))
