"""`roadgaze listen`: print what a Zenoh subscriber receives from roadgaze daemons, checked.

What is received, checked and ordered comes from `roadgaze.transport.consumer.AlertConsumer`
(history, recovery, gaps, duplicates, forged and second publishers); this module prints its
events: checked messages on stdout, what was not printed (and why) on stderr, the totals at
exit. By default `listen` is a client of the rendezvous endpoint (tcp/127.0.0.1:7447), where
`roadgaze run` listens or a router runs.
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import sys
import time
from typing import Any

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
    from roadgaze.transport.consumer import AlertConsumer

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
            consumer = AlertConsumer(
                session,
                keys,
                zconf.prefix,
                history=zconf.alert_cache_size,
                yaw=not args.no_yaw,
                vss_prefix=zconf.vss_prefix if zconf.vss else None,
            )
            with consumer:
                printer = Printer(args, consumer)
                elapsed_s = time.monotonic() - started
                remaining_s = None if timeout_s is None else timeout_s - elapsed_s
                if args.query_state:
                    from roadgaze.commands.listen_query import query_state

                    return query_state(printer, max(0.5, remaining_s or 0.0))
                return printer.follow(remaining_s, stop, endpoints, plan)


class Printer:
    """Prints the events of one `listen` run: checked messages on stdout, the rest on stderr."""

    def __init__(self, args: argparse.Namespace, consumer: Any) -> None:
        from roadgaze.transport import ThrottledWarning

        self.args = args
        self.consumer = consumer
        self.warn = ThrottledWarning(log, "roadgaze listen: message rejected", period_s=5.0)

    def follow(self, timeout_s: float | None, stop: Any, endpoints: str, plan: Any) -> int:
        """Print until `timeout_s`, a stop or `--count`; the totals; the exit status."""
        consumer, count = self.consumer, self.args.count
        printed = 0
        for event in consumer.events(timeout_s, stop.is_set):
            printed += self.handle(event)
            if count is not None and printed >= count:
                break
        for event in consumer.finish():
            printed += self.handle(event)
        _say(consumer.book.totals(consumer.dropped))
        if printed == 0 and timeout_s is not None and not stop.is_set():
            if not consumer.ever_connected:
                _say(
                    f"connected to nothing ({endpoints}) in {timeout_s:g} s: "
                    f"{unreachable_hint(plan)}"
                )
            else:
                _say(
                    f"received nothing on {consumer.keys.prefix}/* in {timeout_s:g} s: is a "
                    "daemon publishing for this vehicle?"
                )
            return 1
        return 0

    def handle(self, event: Any) -> int:
        """Print one event; how many messages were printed on stdout (0 or 1)."""
        from roadgaze.transport import consumer_events as events
        from roadgaze.transport import printable

        match event:
            case events.AlertReceived():
                second = event.describe_second()
                if second is not None:
                    _say(second)
                extra = {} if event.suspicious is None else {"suspicious": event.suspicious}
                if event.late:
                    extra["late"] = "it arrives after later ones (reported missed before)"
                self.show("alert", event.key, event.vehicle_id, event.alert, extra)
            case events.MessageReceived():
                self.show(event.kind, event.key, event.vehicle_id, event.payload)
            case events.PublisherJoined() | events.PublisherGone():
                joined = isinstance(event, events.PublisherJoined)
                self.show("alive", event.key, event.vehicle_id, {"alive": joined})
            case events.VssReceived():
                if self.args.json:
                    print(json.dumps({"type": "vss", "key": event.key, "value": event.value}))
                else:
                    print(format_vss(event.key, event.value))
                sys.stdout.flush()
            case events.AlertsMissed() | events.AlertRefused() | events.SecondPublisher():
                _say(event.describe())
                return 0
            case events.DuplicateAlert():
                reason = f"duplicate or out of order: seq {event.seq}, expected {event.expected}"
                self.warn(f"alert on {printable(event.key, 80)}: {reason}")
                return 0
            case events.MessageRejected():
                self.warn(f"{event.kind} on {printable(event.key, 80)}: {printable(event.reason)}")
                return 0
            case events.LinkUp():
                log.info("roadgaze listen: connected to %s %s", event.whatami, event.remote)
                return 0
            case events.LinkLost():
                log.warning(
                    "roadgaze listen: %s %s gone; waiting for it to come back",
                    event.whatami,
                    event.remote,
                )
                return 0
            case _:
                return 0
        return 1

    def show(
        self,
        kind: str,
        key: str,
        vehicle: str,
        payload: dict[str, Any],
        extra: dict[str, Any] | None = None,
    ) -> None:
        """One message on stdout: readable, or a JSON object with --json; `extra` (a flag) is
        added to the object, or to the end of the line in brackets."""
        if self.args.json:
            record = {"type": kind, "key": key, "vehicle_id": vehicle, "payload": payload}
            print(json.dumps(record | (extra or {})), flush=True)
            return
        line = format_pretty(kind, vehicle, payload, "")
        if extra:
            line += " [" + "; ".join(f"{name.upper()}: {text}" for name, text in extra.items())
            line += "]"
        print(line, flush=True)
