"""Zenoh transport: message schemas, key expressions, the session and what is declared on it.

Under the prefix (default `vehicle/{vehicle_id}/dms`):

- `yaw`: one `YawMessage` per frame, congestion control DROP (a slow subscriber loses yaw
  samples, never delays the pipeline);
- `alert`: one `AlertMessage` per monitor event, priority INTERACTIVE_HIGH, congestion control
  BLOCK (an alert is never dropped by the local queue);
- `alive`: a liveliness token, present while the daemon runs;
- `state`: a queryable answering a `StateMessage` (status, counters, config summary).

The speed input (default `vehicle/{vehicle_id}/speed`) accepts `{"kmh": <number>}` or a bare
number; anything else is logged and ignored. Payloads are the pydantic models below serialised as
JSON with encoding `application/json`.

`ZenohLink` owns the session. When it cannot be opened (client mode and no router, say) the link
is degraded: monitoring goes on, messages are counted as not sent (alerts are kept in a small
bounded queue and sent once connected) and the session is re-opened with backoff in a background
thread. In peer mode Zenoh itself retries the `connect` endpoints; the link reports degraded while
none of them is connected.
"""

from __future__ import annotations

import json
import logging
import math
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field

from roadgaze.config import ZenohConfig
from roadgaze.errors import TransportError

log = logging.getLogger("roadgaze.transport")

YAW_SCHEMA = "roadgaze.yaw/1"
ALERT_SCHEMA = "roadgaze.alert/1"
STATE_SCHEMA = "roadgaze.state/1"
PENDING_ALERTS_MAX = 256
"""Alerts kept while no session is open; the oldest are dropped (and counted) beyond this."""
PENDING_FLUSH_WAIT_S = 2.0
"""After a session (re)opens, how long kept alerts wait for a matching subscriber."""


class _Message(BaseModel):
    model_config = ConfigDict(
        frozen=True,
        populate_by_name=True,
        extra="forbid",
        json_schema_serialization_defaults_required=True,  # every field is always published
    )

    def to_json_bytes(self) -> bytes:
        return self.model_dump_json(by_alias=True).encode("utf-8")


class YawMessage(_Message):
    """One frame's head yaw and road-ahead decision."""

    schema_id: Literal["roadgaze.yaw/1"] = Field(default="roadgaze.yaw/1", alias="schema")
    vehicle_id: str
    seq: int = Field(ge=0, description="Per-key sequence number, from 0 at start.")
    t_s: float = Field(
        description="Source timeline: video time in replay, seconds since start live."
    )
    wall_time: float = Field(description="Unix time (s) when the message was built.")
    frame: int = Field(ge=0)
    face: bool
    yaw_deg: float | None = Field(description="Smoothed yaw, > 0 = head turned to driver's left.")
    yaw_raw_deg: float | None
    yaw_rate_dps: float | None = None
    on_road: bool | None = Field(description="Road ahead; None when no face and not turned away.")
    gaze: Literal["on_road", "off_road", "unknown"]
    neutral_yaw_deg: float
    n_faces: int = Field(default=0, ge=0)


class AlertMessage(_Message):
    """One monitor event (see docs/monitor.md)."""

    schema_id: Literal["roadgaze.alert/1"] = Field(default="roadgaze.alert/1", alias="schema")
    vehicle_id: str
    seq: int = Field(ge=0)
    kind: Literal["long_distraction", "vats", "driver_unavailable", "cleared"]
    level: Literal["info", "warning", "critical"]
    t_s: float
    wall_time: float
    yaw_deg: float | None
    off_road_s: float = Field(ge=0, description="Current continuous off-road time.")
    window_off_road_s: float = Field(ge=0, description="Off-road time in the VATS window.")
    unavailable_s: float = Field(default=0.0, ge=0)
    speed_kmh: float | None = None
    clears: list[Literal["long_distraction", "vats", "driver_unavailable"]] = Field(
        default_factory=list, description="For 'cleared': the alerts it ends."
    )


class TransportStatus(_Message):
    mode: Literal["peer", "client"]
    session_open: bool
    connected: bool
    """Session open and, when `connect` endpoints are configured, at least one is connected."""
    peers: int = 0
    routers: int = 0
    session_reopens: int = 0
    yaw_sent: int = 0
    alerts_sent: int = 0
    not_sent: int = 0
    pending_alerts: int = 0
    speed_messages: int = 0
    speed_rejected: int = 0


class MonitorSnapshot(_Message):
    gaze: Literal["on_road", "off_road", "unknown"]
    on_road: bool
    neutral_yaw_deg: float
    yaw_deg: float | None
    off_road_s: float
    window_off_road_s: float
    unavailable_s: float
    vats_armed: bool
    active_alerts: list[str]
    moving: bool
    speed_kmh: float | None
    speed_source: Literal["none", "waiting", "fresh", "stale"]
    alert_counts: dict[str, int]


class StateMessage(_Message):
    """Answer of the `state` queryable: health, monitor state, counters and config summary."""

    schema_id: Literal["roadgaze.state/1"] = Field(default="roadgaze.state/1", alias="schema")
    vehicle_id: str
    wall_time: float
    status: Literal["starting", "running", "degraded", "stopping", "stopped"]
    problems: list[str] = Field(default_factory=list, description="Why the status is degraded.")
    t_s: float | None = Field(description="Timestamp of the last sample processed.")
    uptime_s: float
    source: str
    source_status: str
    frames: int
    faces: int
    camera_reopens: int = 0
    transport: TransportStatus
    monitor: MonitorSnapshot
    config: dict[str, Any]


MESSAGE_MODELS: dict[str, type[_Message]] = {
    "yaw": YawMessage,
    "alert": AlertMessage,
    "state": StateMessage,
}


def json_schemas() -> dict[str, dict[str, Any]]:
    """The JSON Schema of every published message, by name."""
    return {
        name: model.model_json_schema(by_alias=True, mode="serialization")
        for name, model in MESSAGE_MODELS.items()
    }


@dataclass(frozen=True, slots=True)
class Keys:
    """The key expressions of one vehicle (or of all, with vehicle id `*`)."""

    vehicle_id: str
    prefix: str
    yaw: str
    alert: str
    alive: str
    state: str
    speed: str | None

    @classmethod
    def from_config(cls, config: ZenohConfig, vehicle_id: str | None = None) -> Keys:
        vid = config.vehicle_id if vehicle_id is None else vehicle_id
        try:
            prefix = config.prefix.format(vehicle_id=vid).strip("/")
            speed = config.speed_key.format(vehicle_id=vid).strip("/") or None
        except (KeyError, IndexError, ValueError) as exc:
            raise TransportError(
                f"zenoh.prefix/speed_key may only use the placeholder {{vehicle_id}}: {exc}"
            ) from None
        if not prefix:
            raise TransportError("zenoh.prefix is empty; use e.g. 'vehicle/{vehicle_id}/dms'")
        return cls(
            vehicle_id=vid,
            prefix=prefix,
            yaw=f"{prefix}/yaw",
            alert=f"{prefix}/alert",
            alive=f"{prefix}/alive",
            state=f"{prefix}/state",
            speed=speed,
        )


def session_config_dict(config: ZenohConfig) -> dict[str, Any]:
    """The Zenoh settings roadgaze applies (on top of `config_file` when one is given).

    Without a file every field applies; with a file only the fields set explicitly in roadgaze's
    configuration override it.
    """
    explicit = config.model_fields_set if config.config_file is not None else None

    def wanted(name: str) -> bool:
        return explicit is None or name in explicit

    settings: dict[str, Any] = {}
    if wanted("mode"):
        settings["mode"] = config.mode
    if wanted("connect") and config.connect:
        settings["connect/endpoints"] = list(config.connect)
        # Zenoh retries unreachable endpoints in the background; as often as roadgaze would.
        settings["connect/retry"] = {
            "period_init_ms": round(config.reconnect_initial_s * 1000),
            "period_max_ms": round(config.reconnect_max_s * 1000),
            "period_increase_factor": 2,
        }
    if wanted("listen") and config.mode == "peer":
        settings["listen/endpoints"] = list(config.listen)
    if wanted("multicast_scouting"):
        settings["scouting/multicast/enabled"] = config.multicast_scouting
    if config.mode == "client" and config.connect and wanted("connect"):
        # Zenoh's client refuses to open without a router; roadgaze retries itself instead.
        settings["connect/timeout_ms"] = 2000
    return settings


def zenoh_error_text(exc: BaseException) -> str:
    """Zenoh's error message without the Rust source location it appends."""
    return str(exc).split(" at /")[0].rstrip(". ") or type(exc).__name__


def build_zenoh_config(config: ZenohConfig) -> Any:
    """A `zenoh.Config` from roadgaze's settings; raises TransportError for a bad file or value."""
    import zenoh

    if config.mode == "client" and not config.connect and not config.multicast_scouting:
        raise TransportError(
            "zenoh client mode needs a router: set zenoh.connect (e.g. tcp/127.0.0.1:7447) "
            "or enable zenoh.multicast_scouting"
        )
    try:
        if config.config_file is not None:
            path = Path(config.config_file)
            if not path.is_file():
                raise TransportError(f"zenoh config file {path} not found")
            zconf = zenoh.Config.from_file(str(path))
        else:
            zconf = zenoh.Config()
        for key, value in session_config_dict(config).items():
            zconf.insert_json5(key, json.dumps(value))
    except TransportError:
        raise
    except Exception as exc:  # zenoh raises its own ZError for bad endpoints or files
        raise TransportError(f"bad zenoh configuration: {zenoh_error_text(exc)}") from None
    return zconf


def parse_speed_kmh(payload: bytes) -> float:
    """Speed from a speed message: `{"kmh": <number>}` or a bare number; ValueError otherwise."""
    try:
        value = json.loads(payload.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"not JSON: {payload[:60]!r}") from exc
    if isinstance(value, dict):
        if set(value) != {"kmh"}:
            raise ValueError(f"expected {{'kmh': number}}, found keys {sorted(value)}")
        value = value["kmh"]
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"speed must be a number, found {value!r}")
    speed = float(value)
    if not math.isfinite(speed) or speed < 0:
        raise ValueError(f"speed must be finite and >= 0, found {speed}")
    return speed


class SpeedInput:
    """The latest speed received, thread-safe; stale after `stale_s` of wall time."""

    def __init__(self, stale_s: float, clock: Callable[[], float] = time.monotonic) -> None:
        self._stale_s = stale_s
        self._clock = clock
        self._lock = threading.Lock()
        self._speed_kmh: float | None = None
        self._received_at: float | None = None
        self.messages = 0
        self.rejected = 0

    def on_payload(self, payload: bytes) -> None:
        try:
            speed = parse_speed_kmh(payload)
        except ValueError as exc:
            with self._lock:
                self.rejected += 1
                count = self.rejected
            if count <= 10 or count % 100 == 0:
                log.warning("ignored speed message (%d so far): %s", count, exc)
            return
        with self._lock:
            self._speed_kmh, self._received_at = speed, self._clock()
            self.messages += 1

    def current(self) -> tuple[float | None, Literal["waiting", "fresh", "stale"]]:
        """The speed to use (None: unknown, taken as moving) and where it stands."""
        with self._lock:
            if self._received_at is None:
                return None, "waiting"
            if self._clock() - self._received_at > self._stale_s:
                return None, "stale"
            return self._speed_kmh, "fresh"


class _Declared:
    """Everything declared on one open session; closed together."""

    def __init__(
        self,
        session: Any,
        keys: Keys,
        state_reply: Callable[[], bytes] | None,
        speed: SpeedInput | None,
    ) -> None:
        import zenoh

        self.session = session
        self._entities: list[Any] = []
        try:
            self.yaw = session.declare_publisher(
                keys.yaw,
                encoding=zenoh.Encoding.APPLICATION_JSON,
                congestion_control=zenoh.CongestionControl.DROP,
                priority=zenoh.Priority.DATA,
            )
            self._entities.append(self.yaw)
            self.alert = session.declare_publisher(
                keys.alert,
                encoding=zenoh.Encoding.APPLICATION_JSON,
                congestion_control=zenoh.CongestionControl.BLOCK,
                priority=zenoh.Priority.INTERACTIVE_HIGH,
            )
            self._entities.append(self.alert)
            if speed is not None and keys.speed is not None:
                self._entities.append(
                    session.declare_subscriber(
                        keys.speed, lambda sample: speed.on_payload(sample.payload.to_bytes())
                    )
                )
            if state_reply is not None:
                self._entities.append(
                    session.declare_queryable(keys.state, _state_callback(keys.state, state_reply))
                )
            self._entities.append(session.liveliness().declare_token(keys.alive))
        except BaseException:
            self.close()
            raise

    def close(self) -> None:
        for entity in reversed(self._entities):
            try:
                entity.undeclare()
            except Exception as exc:
                log.debug("undeclare failed: %s", exc)
        self._entities.clear()
        try:
            self.session.close()
        except Exception as exc:
            log.debug("session close failed: %s", exc)


def _state_callback(key: str, state_reply: Callable[[], bytes]) -> Callable[[Any], None]:
    import zenoh

    def on_query(query: Any) -> None:
        try:
            query.reply(key, state_reply(), encoding=zenoh.Encoding.APPLICATION_JSON)
        except Exception:
            log.exception("could not answer a state query")

    return on_query


def open_session(config: ZenohConfig) -> Any:
    """A plain Zenoh session for tools and listeners; raises TransportError when it cannot open."""
    import zenoh

    zconf = build_zenoh_config(config)
    try:
        return zenoh.open(zconf)
    except Exception as exc:
        raise TransportError(
            f"cannot open a zenoh session ({config.mode}): {zenoh_error_text(exc)}"
        ) from None


class ZenohLink:
    """The daemon's session: publishers, speed input, liveliness token and state queryable.

    Use as a context manager. Never raises on publish: failures are counted and logged, and an
    unopenable session is retried in the background with exponential backoff.
    """

    def __init__(
        self,
        config: ZenohConfig,
        keys: Keys,
        state_reply: Callable[[], bytes] | None = None,
        speed: SpeedInput | None = None,
    ) -> None:
        self.config = config
        self.keys = keys
        self._state_reply = state_reply
        self.speed = speed
        self._zconf = build_zenoh_config(config)  # bad settings fail here, at once
        self._lock = threading.Lock()
        self._declared: _Declared | None = None
        self._pending: deque[bytes] = deque(maxlen=PENDING_ALERTS_MAX)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.session_reopens = 0
        self.yaw_sent = 0
        self.alerts_sent = 0
        self.not_sent = 0
        self.last_error: str | None = None

    def __enter__(self) -> ZenohLink:
        self.start()
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    def start(self) -> None:
        if not self._try_open():
            self._thread = threading.Thread(
                target=self._reopen_loop, name="zenoh-reopen", daemon=True
            )
            self._thread.start()

    def _try_open(self) -> bool:
        import zenoh

        try:
            session = zenoh.open(self._zconf)
            declared = _Declared(session, self.keys, self._state_reply, self.speed)
        except Exception as exc:
            self.last_error = zenoh_error_text(exc)
            log.warning("zenoh session not available (%s); monitoring goes on", self.last_error)
            return False
        self.last_error = None
        log.info("zenoh session open (%s), prefix %s", self.config.mode, self.keys.prefix)
        if self._pending:
            # Give subscribers a moment to be matched, so kept alerts reach somebody.
            deadline = time.monotonic() + PENDING_FLUSH_WAIT_S
            while not declared.alert.matching_status.matching and time.monotonic() < deadline:
                if self._stop.wait(0.05):
                    break
        while True:
            with self._lock:
                if self._stop.is_set():
                    declared.close()
                    return True
                pending = list(self._pending)
                self._pending.clear()
                if not pending:
                    self._declared = declared
                    return True
            for payload in pending:
                self._put(declared, payload)

    def _reopen_loop(self) -> None:
        delay_s = self.config.reconnect_initial_s
        while not self._stop.wait(delay_s):
            self.session_reopens += 1
            if self._try_open():
                return
            delay_s = min(delay_s * 2.0, self.config.reconnect_max_s)

    def publish_yaw(self, message: YawMessage) -> None:
        declared = self._declared
        if declared is None:
            self.not_sent += 1
            return
        try:
            declared.yaw.put(message.to_json_bytes())
            self.yaw_sent += 1
        except Exception as exc:
            self.not_sent += 1
            self.last_error = f"yaw put failed: {exc}"

    def publish_alert(self, message: AlertMessage) -> None:
        payload = message.to_json_bytes()
        with self._lock:
            if self._declared is None:
                if len(self._pending) == self._pending.maxlen:
                    self.not_sent += 1
                self._pending.append(payload)
                log.warning("alert %s kept until the zenoh session opens", message.kind)
                return
        self._put_alert(payload)

    def _put_alert(self, payload: bytes) -> None:
        # Never hold the lock while Zenoh may block: its callbacks (state queries) take it too.
        with self._lock:
            declared = self._declared
            if declared is None:
                self._pending.append(payload)
                return
        self._put(declared, payload)

    def _put(self, declared: _Declared, payload: bytes) -> None:
        try:
            declared.alert.put(payload)
            self.alerts_sent += 1
        except Exception as exc:
            self.not_sent += 1
            self.last_error = f"alert put failed: {exc}"
            log.error("alert not sent: %s", exc)

    def status(self) -> TransportStatus:
        with self._lock:
            declared = self._declared
            pending = len(self._pending)
        peers = routers = 0
        if declared is not None:
            try:
                info = declared.session.info
                peers, routers = len(info.peers_zid()), len(info.routers_zid())
            except Exception as exc:
                log.debug("session info failed: %s", exc)
        needs_link = bool(self.config.connect) or self.config.mode == "client"
        connected = declared is not None and (not needs_link or peers + routers > 0)
        speed_messages = self.speed.messages if self.speed is not None else 0
        speed_rejected = self.speed.rejected if self.speed is not None else 0
        return TransportStatus(
            mode=self.config.mode,
            session_open=declared is not None,
            connected=connected,
            peers=peers,
            routers=routers,
            session_reopens=self.session_reopens,
            yaw_sent=self.yaw_sent,
            alerts_sent=self.alerts_sent,
            not_sent=self.not_sent,
            pending_alerts=pending,
            speed_messages=speed_messages,
            speed_rejected=speed_rejected,
        )

    def publish_final_state(self) -> None:
        """Put the current state on the state key (for subscribers; queries get it anyway)."""
        if self._state_reply is None:
            return
        import zenoh

        declared = self._declared
        if declared is None:
            return
        try:
            declared.session.put(
                self.keys.state,
                self._state_reply(),
                encoding=zenoh.Encoding.APPLICATION_JSON,
                congestion_control=zenoh.CongestionControl.BLOCK,
            )
        except Exception as exc:
            log.warning("final state not published: %s", exc)

    def close(self) -> None:
        """Undeclare everything and close the session; idempotent."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5.0)
        with self._lock:
            declared, self._declared = self._declared, None
            if self._pending:
                log.warning("%d alerts never sent: no zenoh session", len(self._pending))
        if declared is not None:
            declared.close()


def add_zenoh_options(parser: Any) -> None:
    """Command-line options shared by run, replay --publish and listen."""
    group = parser.add_argument_group("zenoh")
    group.add_argument("--vehicle-id", metavar="ID", help="vehicle id in the key expressions")
    group.add_argument(
        "--zenoh-connect",
        action="append",
        metavar="ENDPOINT",
        help="endpoint to connect to, e.g. tcp/127.0.0.1:7447 (repeatable)",
    )
    group.add_argument(
        "--zenoh-listen",
        action="append",
        metavar="ENDPOINT",
        help="endpoint to listen on (repeatable; default tcp/127.0.0.1:0)",
    )
    group.add_argument("--zenoh-mode", choices=["peer", "client"], help="zenoh session mode")


def zenoh_config_from_args(config: ZenohConfig, args: Any) -> ZenohConfig:
    """`config` with the --vehicle-id/--zenoh-* options applied (validated again)."""
    update: dict[str, Any] = {}
    if getattr(args, "vehicle_id", None) and args.vehicle_id != "*":
        update["vehicle_id"] = args.vehicle_id
    if getattr(args, "zenoh_connect", None):
        update["connect"] = list(args.zenoh_connect)
    if getattr(args, "zenoh_listen", None):
        update["listen"] = list(args.zenoh_listen)
    if getattr(args, "zenoh_mode", None):
        update["mode"] = args.zenoh_mode
    if not update:
        return config
    from pydantic import ValidationError

    from roadgaze.errors import ConfigError

    merged = {name: getattr(config, name) for name in config.model_fields_set} | update
    try:
        return ZenohConfig.model_validate(merged)
    except ValidationError as exc:
        problems = "; ".join(f"{'.'.join(map(str, e['loc']))}: {e['msg']}" for e in exc.errors())
        raise ConfigError(f"bad zenoh option: {problems}") from None
