"""`roadgaze listen`: print what a Zenoh subscriber receives from roadgaze daemons."""

from __future__ import annotations

import argparse
import json
import queue
import sys
import time
from typing import Any

from roadgaze.commands.options import add_zenoh_options, common_options, zenoh_config_from_args
from roadgaze.config import Config


def register(subparsers: Any) -> None:
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "listen",
        parents=[common_options()],
        help="print the yaw, alert, state and liveliness messages of one vehicle (or all), and "
        "with --vss the COVESA VSS signals",
        description="Subscribe to vehicle/<id>/dms/{yaw,alert,state} and the liveliness token "
        "vehicle/<id>/dms/alive, and print each message: readable lines, or one JSON object per "
        "line with --json. Without --vehicle-id every vehicle is shown. With --query-state, ask "
        "the state queryable once, print the answers and exit: 0 when every answer says running, "
        "3 when one is degraded (or starting/stopping), 1 without an answer (a health check). "
        "With --vss, also the COVESA VSS driver signals (Vehicle/**, under zenoh.vss_prefix).",
    )
    add_zenoh_options(parser)
    parser.add_argument("--json", action="store_true", help="one JSON object per line")
    parser.add_argument("--no-yaw", action="store_true", help="do not print yaw messages")
    parser.add_argument("--count", type=int, metavar="N", help="exit after N messages")
    parser.add_argument("--timeout", type=float, metavar="S", help="exit after S seconds")
    parser.add_argument("--query-state", action="store_true", help="query the state once and exit")
    parser.set_defaults(handler=run)


def _kind_of(key: str) -> str:
    return key.rsplit("/", 1)[-1]


def _vehicle_of(key: str, prefix_template: str) -> str:
    parts = prefix_template.strip("/").split("/")
    if "{vehicle_id}" in parts:
        index = parts.index("{vehicle_id}")
        key_parts = key.split("/")
        if index < len(key_parts):
            return key_parts[index]
    return "?"


def format_pretty(kind: str, vehicle: str, payload: dict[str, Any] | None, raw: str) -> str:
    """One readable line for a received message."""
    if payload is None:
        return f"{kind:<6} {vehicle} undecodable payload: {raw[:120]}"
    if kind == "alive":
        return f"alive  {vehicle} {'joined' if payload.get('alive') else 'left'}"
    if kind == "alert":
        yaw = payload.get("yaw_deg")
        yaw_text = "no face" if yaw is None else f"yaw={yaw:+.1f}°"
        text = (
            f"ALERT  {vehicle} #{payload.get('seq')} {payload.get('kind')} "
            f"{payload.get('level')} t={payload.get('t_s', 0.0):.2f}s "
            f"off_road={payload.get('off_road_s', 0.0):.2f}s "
            f"window={payload.get('window_off_road_s', 0.0):.2f}s {yaw_text}"
        )
        if payload.get("clears"):
            text += " clears=" + ",".join(payload["clears"])
        if payload.get("closure_s"):
            text += f" closure={payload['closure_s']:.2f}s"
        if payload.get("reason"):
            text += f" ({payload['reason']})"
        return text
    if kind == "yaw":
        yaw = payload.get("yaw_deg")
        yaw_text = "    --  " if yaw is None else f"{yaw:+7.1f}°"
        line = f"yaw    {vehicle} #{payload.get('seq')} t={payload.get('t_s', 0.0):.2f}s {yaw_text}"
        if "zone" not in payload:  # roadgaze.yaw/1
            return f"{line} {payload.get('gaze')}"
        pitch = payload.get("pitch_deg")
        pitch_text = "    --  " if pitch is None else f"{pitch:+7.1f}°"
        line = f"{line} pitch {pitch_text} {payload.get('zone') or payload.get('gaze')}"
        if "eyes" not in payload:  # roadgaze.yaw/2
            return line
        return f"{line} {_eyes_text(payload)}"
    if kind == "state":
        transport = payload.get("transport", {})
        return (
            f"state  {vehicle} status={payload.get('status')} frames={payload.get('frames')} "
            f"alerts_sent={transport.get('alerts_sent')} problems={payload.get('problems')}"
        )
    return f"{kind:<6} {vehicle} {raw[:200]}"


def _eyes_text(payload: dict[str, Any]) -> str:
    """The eyes of a yaw/3 message in a few words: state, openness, gaze, closure, PERCLOS."""
    eyes = str(payload.get("eyes"))
    openness = payload.get("eye_openness")
    text = f"eyes {eyes}" + ("" if openness is None else f" {openness:.2f}")
    gaze = payload.get("gaze_yaw_deg")
    if gaze is not None and payload.get("gaze_source") == "eyes":
        text += f" gaze {gaze:+.1f}°/{payload.get('gaze_pitch_deg') or 0.0:+.1f}°"
    if payload.get("closure_s"):
        text += f" closed {payload['closure_s']:.1f}s"
    if payload.get("perclos") is not None:
        text += f" perclos {payload['perclos']:.2f}"
    if payload.get("degraded"):
        text += " DEGRADED"
    return text


def format_vss(key: str, raw: bytes) -> str:
    """One readable line for a VSS value: `vss    Vehicle/Driver/IsEyesOnRoad = true`."""
    return f"vss    {key} = {raw.decode('utf-8', errors='replace')[:60]}"


def _decode(raw: bytes) -> tuple[dict[str, Any] | None, str]:
    text = raw.decode("utf-8", errors="replace")
    try:
        value = json.loads(text)
    except json.JSONDecodeError:
        return None, text
    return (value if isinstance(value, dict) else None), text


def run(args: argparse.Namespace, config: Config) -> int:
    import zenoh

    from roadgaze.transport import Keys, open_session, vss_key

    zconf = zenoh_config_from_args(config.zenoh, args)
    keys = Keys.from_config(zconf, args.vehicle_id or "*")
    deadline = None if args.timeout is None else time.monotonic() + args.timeout
    received: queue.Queue[tuple[str, str, bytes]] = queue.Queue(maxsize=10_000)
    dropped = 0

    def emit(kind: str, key: str, payload: bytes) -> None:
        nonlocal dropped
        try:
            received.put_nowait((kind, key, payload))
        except queue.Full:
            dropped += 1

    def print_line(kind: str, key: str, raw: bytes) -> None:
        if kind == "vss":
            if args.json:
                text = raw.decode("utf-8", errors="replace")
                print(json.dumps({"type": "vss", "key": key, "value": text}), flush=True)
            else:
                print(format_vss(key, raw), flush=True)
            return
        payload, text = _decode(raw)
        vehicle = _vehicle_of(key, zconf.prefix)
        if args.json:
            record = {"type": kind, "key": key, "vehicle_id": vehicle, "payload": payload}
            if payload is None:
                record["raw"] = text
            print(json.dumps(record), flush=True)
        else:
            print(format_pretty(kind, vehicle, payload, text), flush=True)

    with open_session(zconf) as session:
        if args.query_state:
            timeout_s = 5.0 if args.timeout is None else args.timeout
            statuses: list[str] = []
            query_deadline = time.monotonic() + timeout_s
            while not statuses and time.monotonic() < query_deadline:
                # Right after opening, the routes to the queryable may not be known yet: ask again.
                wait_s = max(0.05, min(1.0, query_deadline - time.monotonic()))
                for reply in session.get(keys.state, timeout=wait_s):
                    if reply.ok is not None:
                        raw = reply.ok.payload.to_bytes()
                        print_line("state", str(reply.ok.key_expr), raw)
                        payload, _ = _decode(raw)
                        statuses.append(str((payload or {}).get("status")))
            if not statuses:
                print(f"roadgaze listen: no answer from {keys.state}", file=sys.stderr)
                return 1
            return 0 if all(status == "running" for status in statuses) else 3

        def on_data(sample: Any) -> None:
            key = str(sample.key_expr)
            emit(_kind_of(key), key, sample.payload.to_bytes())

        def on_alive(sample: Any) -> None:
            alive = sample.kind == zenoh.SampleKind.PUT
            emit("alive", str(sample.key_expr), json.dumps({"alive": alive}).encode())

        entities = [session.declare_subscriber(keys.alert, on_data)]
        entities.append(session.declare_subscriber(keys.state, on_data))
        if not args.no_yaw:
            entities.append(session.declare_subscriber(keys.yaw, on_data))
        entities.append(session.liveliness().declare_subscriber(keys.alive, on_alive, history=True))
        if zconf.vss:
            vss_keys = vss_key("Vehicle.**", zconf.vss_prefix)

            def on_vss(sample: Any) -> None:
                emit("vss", str(sample.key_expr), sample.payload.to_bytes())

            entities.append(session.declare_subscriber(vss_keys, on_vss))
        printed = 0
        try:
            while args.count is None or printed < args.count:
                wait_s = 0.2 if deadline is None else min(0.2, deadline - time.monotonic())
                if wait_s <= 0:
                    break
                try:
                    kind, key, raw = received.get(timeout=wait_s)
                except queue.Empty:
                    continue
                print_line(kind, key, raw)
                printed += 1
        except KeyboardInterrupt:
            pass
        finally:
            for entity in entities:
                entity.undeclare()
        if dropped:
            print(f"roadgaze listen: {dropped} messages dropped", file=sys.stderr)
    return 0
