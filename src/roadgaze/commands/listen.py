"""`roadgaze listen`: print what a Zenoh subscriber receives from roadgaze daemons, checked.

Alerts come through Zenoh's advanced subscriber (history: the last alerts when it joins or when
a daemon appears; recovery: alerts missed during a link outage), so every alert is printed once,
in `seq` order. Every message is checked (`MessageChecker`) before it is printed; rejected ones
are reported on stderr. By default `listen` is a client of the rendezvous endpoint
(tcp/127.0.0.1:7447), where `roadgaze run` listens or a router runs.
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import queue
import sys
import time
from typing import Any

from roadgaze.commands.listen_alerts import AlertBook
from roadgaze.commands.listen_lines import format_pretty as format_pretty
from roadgaze.commands.listen_lines import format_vss as format_vss
from roadgaze.commands.options import (
    add_zenoh_options,
    check_seconds,
    common_options,
    zenoh_config_from_args,
)
from roadgaze.config import Config
from roadgaze.transport.checks import vehicle_of
from roadgaze.transport.session import unreachable_hint

log = logging.getLogger("roadgaze.listen")
QUEUE_SIZE = 10_000
VSS_MAX_BYTES = 256
"""A VSS value is a short text; anything longer is refused unread."""
LEFT_HOLD_S = 0.5
"""An `alive ... left` waits this long for the vehicle's final state, printed before it."""
ALIVE_HISTORY_S = 0.5
"""At start, how long the liveliness history may take before alerts are subscribed (so a
running daemon's `alive ... joined` comes before its cached alerts)."""


def register(subparsers: Any) -> None:
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "listen",
        parents=[common_options()],
        help="print the yaw, alert, state and liveliness messages of one vehicle (or all), and "
        "with --vss the COVESA VSS signals",
        description="Subscribe to vehicle/<id>/dms/{yaw,alert,state} and the liveliness token "
        "vehicle/<id>/dms/alive and print each checked message: readable lines, or one JSON "
        "object per line with --json. Without --vehicle-id (or with '*') every vehicle is shown. "
        "Alerts arrive complete and in order (history and recovery from the daemon's cache). "
        "By default listen connects as a client to zenoh.rendezvous (tcp/127.0.0.1:7447). "
        "--timeout S exits 1 when nothing was connected or received in S seconds. With "
        "--query-state, ask the state queryable once, print the answers and exit: 0 when every "
        "answer says running, 3 when one is degraded (or starting/stopping) or a vehicle "
        "answered twice, 1 without an answer (a health check). With --vss, also the COVESA VSS "
        "driver signals (Vehicle/**, under zenoh.vss_prefix), each value checked.",
    )
    add_zenoh_options(parser)
    parser.add_argument("--json", action="store_true", help="one JSON object per line")
    parser.add_argument("--no-yaw", action="store_true", help="do not print yaw messages")
    parser.add_argument("--count", type=int, metavar="N", help="exit after N messages")
    parser.add_argument("--timeout", type=float, metavar="S", help="exit after S seconds")
    parser.add_argument("--query-state", action="store_true", help="query the state once and exit")
    parser.set_defaults(handler=run)


def _vehicle_of(key: str, prefix_template: str) -> str:
    return vehicle_of(key, prefix_template)


def _say(text: str) -> None:
    print(f"roadgaze listen: {text}", file=sys.stderr, flush=True)


def run(args: argparse.Namespace, config: Config) -> int:
    from roadgaze.errors import TransportError
    from roadgaze.service.signals import StopFlag, signal_handlers
    from roadgaze.transport import Keys, build_zenoh_config, open_session, plan_session

    # Non-UTF-8 text (a lone surrogate in a hostile payload) is escaped, never a crash.
    for stream in (sys.stdout, sys.stderr):
        reconfigure = getattr(stream, "reconfigure", None)
        if reconfigure is not None:
            reconfigure(errors="backslashreplace")
    check_seconds("--timeout", args.timeout)
    all_vehicles = args.vehicle_id in (None, "*")
    zconf = zenoh_config_from_args(
        config.zenoh, argparse.Namespace(**{**vars(args), "vehicle_id": None})
    )
    keys = Keys.matching(zconf, None if all_vehicles else args.vehicle_id)
    plan = plan_session(zconf, "consumer", mode=args.zenoh_mode)
    plan = build_zenoh_config(plan)[1]  # endpoints as the session will use them
    endpoints = ", ".join(plan.connect + plan.listen) or "no endpoint"
    timeout_s = args.timeout if args.timeout is not None else 5.0 if args.query_state else None
    stop = StopFlag()
    with signal_handlers(stop, doing="stopping", log_name=log.name):
        started = time.monotonic()
        log.info("roadgaze listen: %s; keys %s/*", plan.describe(), keys.prefix)
        if all_vehicles and plan.config_file is not None:
            log.warning(
                "roadgaze listen: with access control (roadgaze security init) a subscription "
                "to every vehicle is denied: name the vehicle with --vehicle-id"
            )
        try:
            session = open_session(
                plan, wait_s=math.inf if timeout_s is None else timeout_s, stopped=stop.is_set
            )
        except TransportError:
            if stop.is_set():
                return 0
            if timeout_s is None:
                raise
            _say(f"connected to nothing ({endpoints}) in {timeout_s:g} s: {unreachable_hint(plan)}")
            return 1
        with session:
            listener = _Listener(args, zconf.prefix, keys, session, zconf.alert_cache_size, plan)
            if zconf.vss:
                listener.vss_prefix = zconf.vss_prefix
            remaining_s = None if timeout_s is None else timeout_s - (time.monotonic() - started)
            try:
                if args.query_state:
                    return listener.query_state(max(0.5, remaining_s or 0.0))
                return listener.follow(remaining_s, stop, endpoints)
            finally:
                listener.close()


class _Listener:
    """The subscriptions of one `listen` run and the printing of what they receive."""

    def __init__(
        self,
        args: argparse.Namespace,
        prefix_template: str,
        keys: Any,
        session: Any,
        history: int,
        plan: Any = None,
    ) -> None:
        import zenoh

        from roadgaze.transport import MESSAGE_MAX_BYTES, ThrottledWarning
        from roadgaze.transport.checks import MessageChecker

        self.args = args
        self.plan = plan
        self.keys = keys
        self.session = session
        self.prefix_template = prefix_template
        self.history = history
        self.checker = MessageChecker(prefix_template)
        self.max_bytes = MESSAGE_MAX_BYTES
        self.received: queue.Queue[tuple[str, str, bytes | int, str | None]] = queue.Queue(
            QUEUE_SIZE
        )
        self.dropped = 0
        self.connected: set[str] = set()
        self.ever_connected = False
        self.warn = ThrottledWarning(log, "roadgaze listen: message rejected", period_s=5.0)
        self.book = AlertBook()
        self._left: dict[str, tuple[float, str, dict[str, Any]]] = {}
        """Vehicle -> (deadline, key, payload) of an `alive ... left` held for its final state."""
        self._alive_seen = False
        self.vss_prefix: str | None = None
        """With --vss: the prefix of the VSS keys ('' for the bare paths); None: not shown."""
        self._sample_kind_put = zenoh.SampleKind.PUT
        self.entities: list[Any] = [
            session.info.declare_transport_events_listener(self._on_transport, history=True)
        ]

    def _on_transport(self, event: Any) -> None:
        zid = str(event.transport.zid)
        whatami = str(event.transport.whatami).rsplit(".", 1)[-1].lower()
        if event.kind == self._sample_kind_put:
            self.connected.add(zid)
            self.ever_connected = True
            log.info("roadgaze listen: connected to %s %s", whatami, zid)
        else:
            self.connected.discard(zid)
            log.warning("roadgaze listen: %s %s gone; waiting for it to come back", whatami, zid)

    def _emit(self, kind: str, key: str, data: bytes | int, source: str | None = None) -> None:
        try:
            self.received.put_nowait((kind, key, data, source))
        except queue.Full:
            self.dropped += 1

    def _on_sample(self, sample: Any) -> None:
        """O(1): size check before any copy, then hand over to the printing loop."""
        key = str(sample.key_expr)
        kind = key.rsplit("/", 1)[-1]
        size = len(sample.payload)
        info = sample.source_info
        source = None if info is None else str(info.source_id)
        self._emit(kind, key, size if size > self.max_bytes else sample.payload.to_bytes(), source)

    def _on_vss(self, sample: Any) -> None:
        """O(1) like `_on_sample`; the value is checked when printed (the bus is untrusted)."""
        size = len(sample.payload)
        data = size if size > VSS_MAX_BYTES else sample.payload.to_bytes()
        self._emit("vss", str(sample.key_expr), data)

    def _on_alive(self, sample: Any) -> None:
        alive = sample.kind == self._sample_kind_put
        self._alive_seen = True
        self._emit("alive", str(sample.key_expr), json.dumps({"alive": alive}).encode())

    def _on_miss(self, miss: Any) -> None:
        self._emit("missed", self.keys.alert, int(miss.nb), str(miss.source))

    def follow(self, timeout_s: float | None, stop: Any, endpoints: str) -> int:
        from zenoh.ext import HistoryConfig, RecoveryConfig, declare_advanced_subscriber

        session, keys = self.session, self.keys
        # Liveliness first: a running daemon's `joined` is printed before its cached alerts.
        self.entities.append(
            session.liveliness().declare_subscriber(keys.alive, self._on_alive, history=True)
        )
        alive_deadline = time.monotonic() + ALIVE_HISTORY_S
        while not self._alive_seen and time.monotonic() < alive_deadline and not stop.is_set():
            time.sleep(0.02)
        alerts = declare_advanced_subscriber(
            session,
            keys.alert,
            self._on_sample,
            history=HistoryConfig(detect_late_publishers=True, max_samples=self.history),
            recovery=RecoveryConfig(heartbeat=True),  # type: ignore[call-arg]  # stub: both required
        )
        self.entities.append(alerts)
        self.entities.append(alerts.sample_miss_listener(self._on_miss))
        self.entities.append(session.declare_subscriber(keys.state, self._on_sample))
        if not self.args.no_yaw:
            self.entities.append(session.declare_subscriber(keys.yaw, self._on_sample))
        if self.vss_prefix is not None:
            from roadgaze.transport import vss_key

            self.entities.append(
                session.declare_subscriber(vss_key("Vehicle.**", self.vss_prefix), self._on_vss)
            )
        deadline = None if timeout_s is None else time.monotonic() + timeout_s
        printed = 0
        while not stop.is_set() and (self.args.count is None or printed < self.args.count):
            printed += self._release_left(time.monotonic())
            wait_s = 0.2 if deadline is None else min(0.2, deadline - time.monotonic())
            if self._left:
                wait_s = min(wait_s, 0.05)
            if wait_s <= 0:
                break
            try:
                kind, key, data, source = self.received.get(timeout=wait_s)
            except queue.Empty:
                continue
            printed += self._print(kind, key, data, source)
        printed += self._release_left(math.inf)
        for line in self.book.unmatched_misses():
            _say(line)
        _say(self.book.totals(self.dropped))
        if printed == 0 and timeout_s is not None and not stop.is_set():
            if not self.ever_connected:
                _say(
                    f"connected to nothing ({endpoints}) in {timeout_s:g} s: "
                    f"{unreachable_hint(self.plan)}"
                )
            else:
                _say(
                    f"received nothing on {self.keys.prefix}/* in {timeout_s:g} s: is a daemon "
                    "publishing for this vehicle?"
                )
            return 1
        return 0

    def _print(self, kind: str, key: str, data: bytes | int, source: str | None) -> int:
        from roadgaze.transport import PayloadError, printable

        if kind == "vss":
            return self._print_vss(key, data)
        vehicle = vehicle_of(key, self.prefix_template)
        if kind == "missed":
            self.book.on_zenoh_miss(str(source), int(data))
            return 0
        if isinstance(data, int):
            self.book.rejected += 1
            self.warn(f"{kind} on {printable(key, 80)}: {data} bytes, limit {self.max_bytes}")
            return 0
        if kind == "alive":
            payload: dict[str, Any] = json.loads(data)
            self.book.on_alive(vehicle, bool(payload["alive"]))
            if not payload["alive"]:  # printed after the vehicle's final state, if it comes
                self._left[vehicle] = (time.monotonic() + LEFT_HOLD_S, key, payload)
                return 0
            self._left.pop(vehicle, None)
        else:
            try:
                checked = self.checker.check(kind, key, data, source)
            except PayloadError as exc:
                self.book.rejected += 1
                self.warn(f"{kind} on {printable(key, 80)}: {printable(str(exc))}")
                return 0
            payload = checked.payload
            if kind == "alert" and not self._own_alert(checked, vehicle, source):
                return 0
        self._show(kind, key, vehicle, payload)
        if kind == "state" and vehicle in self._left:
            return 1 + self._release_left(math.inf, vehicle)
        return 1

    def _own_alert(self, checked: Any, vehicle: str, source: str | None) -> bool:
        """False (after saying why) for an alert of another publisher; reports a gap before it."""
        payload = checked.payload
        seq = payload["seq"]
        foreign = self.book.foreign_source(vehicle, source)
        if foreign is not None:
            self.book.foreign += 1
            _say(
                f"SUSPICIOUS alert #{seq} {payload['kind']} {payload['level']} of {vehicle} from "
                f"{foreign}: not printed (another process publishes this vehicle's alerts; see "
                "docs/security.md)"
            )
            return False
        gap = self.book.gap(vehicle, str(source), seq, checked.missing_before, checked.first)
        if gap is not None:
            _say(gap)
        self.book.printed += 1
        return True

    def _release_left(self, now: float, only: str | None = None) -> int:
        """Print the held `alive ... left` lines whose wait is over (or `only`'s); count them."""
        due = [
            vehicle
            for vehicle, (deadline, _, _) in self._left.items()
            if (only is None or vehicle == only) and deadline <= now
        ]
        for vehicle in due:
            _, key, payload = self._left.pop(vehicle)
            self._show("alive", key, vehicle, payload)
        return len(due)

    def _print_vss(self, key: str, data: bytes | int) -> int:
        from roadgaze.transport import PayloadError, parse_vss_text, printable

        try:
            if isinstance(data, int):
                raise PayloadError(f"{data} bytes, limit {VSS_MAX_BYTES}")
            value = parse_vss_text(key, data, self.vss_prefix or "")
        except PayloadError as exc:
            self.warn(f"vss on {printable(key, 80)}: {printable(str(exc))}")
            return 0
        if self.args.json:
            print(json.dumps({"type": "vss", "key": key, "value": value}), flush=True)
        else:
            print(format_vss(key, value), flush=True)
        return 1

    def _show(self, kind: str, key: str, vehicle: str, payload: dict[str, Any]) -> None:
        if self.args.json:
            record = {"type": kind, "key": key, "vehicle_id": vehicle, "payload": payload}
            print(json.dumps(record), flush=True)
        else:
            print(format_pretty(kind, vehicle, payload, ""), flush=True)

    def query_state(self, timeout_s: float) -> int:
        """Ask every state queryable (no consolidation: a second answerer is seen) and print."""
        from roadgaze.commands.listen_query import query_state

        return query_state(self, timeout_s)

    def close(self) -> None:
        for entity in reversed(self.entities):
            try:
                entity.undeclare()
            except Exception as exc:
                log.debug("undeclare failed: %s", exc)
