"""Zenoh session configuration: which endpoints a daemon or a consumer uses, and opening it.

Without `connect` and `listen` (and without a Zenoh config file) everything meets at the
rendezvous endpoint, `tcp/127.0.0.1:7447` by default: the daemon connects there when something
already listens (a zenohd router, `roadgaze router` or another daemon) and otherwise listens
there itself; consumers (`roadgaze listen`) connect there as clients. `SessionPlan` says what
was chosen so the commands can log it.
"""

from __future__ import annotations

import json
import logging
import re
import socket
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from roadgaze.config import ZenohConfig
from roadgaze.errors import ConfigError, TransportError

log = logging.getLogger(__name__)

Role = Literal["daemon", "consumer"]
RENDEZVOUS_PROBE_S = 0.3
LOOPBACK_HOSTS = ("127.", "[::1]", "localhost")


@dataclass(frozen=True, slots=True)
class SessionPlan:
    """The session a command opens: mode, endpoints and why (for the start-up log line)."""

    mode: str
    connect: tuple[str, ...]
    listen: tuple[str, ...]
    settings: dict[str, Any]
    """Zenoh config paths and values applied on top of the file (or of Zenoh's defaults)."""
    config_file: Path | None = None
    note: str = ""

    def describe(self) -> str:
        """One line: 'peer session, listening on tcp/127.0.0.1:7447 (...)'."""
        parts = [f"{self.mode} session"]
        if self.config_file is not None:
            parts.append(f"from {self.config_file}")
        if self.listen:
            parts.append("listening on " + ", ".join(self.listen))
        parts.append(
            "connecting to " + ", ".join(self.connect) if self.connect else "connecting nowhere"
        )
        text = ", ".join(parts)
        return f"{text} ({self.note})" if self.note else text


def endpoint_in_use(endpoint: str, timeout_s: float = RENDEZVOUS_PROBE_S) -> bool:
    """Whether something accepts TCP connections at a `tcp/HOST:PORT` or `tls/HOST:PORT`
    endpoint; True for other protocols (they cannot be probed, so they are connected to)."""
    protocol, _, address = endpoint.partition("/")
    if protocol not in ("tcp", "tls"):
        return True
    host, _, port = address.rpartition(":")
    host = host.strip("[]").split("#")[0]
    try:
        with socket.create_connection((host, int(port.split("#")[0])), timeout=timeout_s):
            return True
    except (OSError, ValueError):
        return False


def insecure_endpoints(endpoints: tuple[str, ...] | list[str]) -> list[str]:
    """Endpoints that leave the machine without TLS (the daemon warns about them at start)."""
    insecure = []
    for endpoint in endpoints:
        protocol, _, address = endpoint.partition("/")
        if protocol not in ("tls", "quic") and not address.startswith(LOOPBACK_HOSTS):
            insecure.append(endpoint)
    return insecure


def _retry(config: ZenohConfig) -> dict[str, Any]:
    # Zenoh's default (1 s doubling to 4 s) can add 4 s before a restarted router is seen.
    return {
        "period_init_ms": round(config.reconnect_initial_s * 1000),
        "period_max_ms": round(config.reconnect_max_s * 1000),
        "period_increase_factor": 2,
    }


def plan_session(
    config: ZenohConfig,
    role: Role = "daemon",
    probe: Callable[[str], bool] = endpoint_in_use,
    mode: str | None = None,
) -> SessionPlan:
    """The session for `role`. A daemon uses `config.mode`; a consumer is a client unless `mode`
    says peer (two peers linked only through a router do not hear each other).

    With a Zenoh config file only the fields set explicitly in roadgaze's configuration override
    the file; without one, every field applies and the rendezvous fills in missing endpoints.
    """
    explicit = config.model_fields_set if config.config_file is not None else None

    def wanted(name: str) -> bool:
        return explicit is None or name in explicit

    chosen_mode = mode or (config.mode if role == "daemon" else "client")
    connect, listen, note = list(config.connect), list(config.listen), ""
    if explicit is None and not connect and not listen and config.rendezvous:
        rendezvous = config.rendezvous
        if role == "consumer" or chosen_mode == "client" or probe(rendezvous):
            connect = [rendezvous]
            if role == "daemon":
                note = "the rendezvous; a router or another daemon listens there"
        else:
            listen = [rendezvous]
            note = "the rendezvous; nothing listened there: consumers connect here"
    settings: dict[str, Any] = {}
    if wanted("mode") or mode is not None:
        settings["mode"] = chosen_mode
    if connect and (wanted("connect") or explicit is None):
        settings["connect/endpoints"] = connect
        settings["connect/retry"] = _retry(config)
    if chosen_mode == "peer" and (wanted("listen") or explicit is None):
        settings["listen/endpoints"] = listen
    elif chosen_mode == "client":
        listen = []
        if explicit is None or wanted("listen"):
            settings["listen/endpoints"] = []
    if wanted("multicast_scouting"):
        settings["scouting/multicast/enabled"] = config.multicast_scouting
    return SessionPlan(
        mode=chosen_mode,
        connect=tuple(connect),
        listen=tuple(listen),
        settings=settings,
        config_file=config.config_file,
        note=note,
    )


def zenoh_error_text(exc: BaseException) -> str:
    """Zenoh's error message without the Rust source location it appends, on one line (a
    JSON5 syntax error's "--> LINE:COLUMN" and "= expected ..." become "line L, column C:
    expected ...")."""
    text = str(exc).split(" at /")[0].rstrip(". ") or type(exc).__name__
    where = re.search(r"-->\s*(\d+):(\d+)", text)
    expected = re.search(r"=\s*(.+)$", text.strip())
    if where and expected:
        return f"line {where[1]}, column {where[2]}: {expected[1].strip()} (JSON5 syntax)"
    return " ".join(text.split())


def load_zenoh_file(path: Path) -> Any:
    """`zenoh.Config.from_file(path)`; TransportError in one line naming the file when it is
    missing, a folder, unreadable or not valid JSON5 / a valid Zenoh config."""
    import zenoh

    if path.is_dir():
        raise TransportError(f"zenoh config file {path} is a folder; pass its zenoh.json5 file")
    if not path.is_file():
        raise TransportError(f"zenoh config file {path} not found")
    try:
        return zenoh.Config.from_file(str(path))
    except Exception as exc:  # zenoh's ZError: syntax, unknown keys, bad values, permissions
        raise TransportError(f"bad zenoh config file {path}: {zenoh_error_text(exc)}") from None


def _endpoints_of(zconf: Any, path: str, mode: str) -> tuple[str, ...]:
    try:
        value = json.loads(zconf.get_json(path))
    except Exception:  # absent or not readable back: nothing to report
        return ()
    if isinstance(value, dict):  # per-mode endpoints: {"router": [...], "peer": [...]}
        value = value.get(mode, [])
    return tuple(str(item) for item in value) if isinstance(value, list) else ()


def build_zenoh_config(plan: SessionPlan) -> tuple[Any, SessionPlan]:
    """A `zenoh.Config` for `plan`, and the plan with the endpoints read back from it (a config
    file may set them). Raises TransportError for a bad file or value."""
    import zenoh

    try:
        if plan.config_file is not None:
            zconf = load_zenoh_file(Path(plan.config_file))
        else:
            zconf = zenoh.Config()
        for key, value in plan.settings.items():
            zconf.insert_json5(key, json.dumps(value))
        mode = str(json.loads(zconf.get_json("mode")) or "peer")
    except TransportError:
        raise
    except Exception as exc:  # zenoh raises its own ZError for bad endpoints or files
        raise TransportError(f"bad zenoh configuration: {zenoh_error_text(exc)}") from None
    connect = _endpoints_of(zconf, "connect/endpoints", mode)
    listen = _endpoints_of(zconf, "listen/endpoints", mode) if mode != "client" else ()
    if mode == "client" and not connect:
        raise TransportError(
            "a zenoh client needs a router or daemon to connect to: set zenoh.connect "
            "(e.g. tcp/127.0.0.1:7447) or zenoh.rendezvous"
        )
    resolved = SessionPlan(mode, connect, listen, plan.settings, plan.config_file, plan.note)
    return zconf, resolved


def open_session(
    plan: SessionPlan,
    wait_s: float = 0.0,
    stopped: Callable[[], bool] = lambda: False,
    retry_s: float = 0.25,
) -> Any:
    """Open a session for `plan`. A client cannot open before its router (or daemon) answers:
    it is retried every `retry_s` for up to `wait_s` (forever with `math.inf`) unless
    `stopped()`. Raises TransportError when it cannot open."""
    import zenoh

    zconf, plan = build_zenoh_config(plan)
    deadline = time.monotonic() + wait_s
    announced = False
    while True:
        try:
            return zenoh.open(zconf)
        except Exception as exc:
            reason = zenoh_error_text(exc)
        if stopped() or time.monotonic() + retry_s > deadline:
            raise TransportError(
                f"cannot open a zenoh session ({plan.describe()}): {reason}; "
                f"{unreachable_hint(plan)}"
            ) from None
        if not announced:
            log.info("waiting for a router or daemon (%s)", plan.describe())
            hint = unreachable_hint(plan)
            if hint.startswith("something listens"):  # it will not get better by waiting
                log.warning("zenoh session refused (%s): %s", reason, hint)
            announced = True
        time.sleep(retry_s)


def certificate_name(zconf: Any) -> str | None:
    """The common name of the client certificate a Zenoh config presents (mutual TLS), or None
    when it presents none or the file cannot be read (Zenoh itself reports that)."""
    try:
        path = json.loads(zconf.get_json("transport/link/tls/connect_certificate"))
    except Exception:
        return None
    if not isinstance(path, str) or not path:
        return None
    try:
        from cryptography import x509
        from cryptography.x509.oid import NameOID

        certificate = x509.load_pem_x509_certificate(Path(path).read_bytes())
        names = certificate.subject.get_attributes_for_oid(NameOID.COMMON_NAME)
    except (OSError, ValueError):
        return None
    return str(names[0].value) if names else None


def check_daemon_file(zconf: Any, plan: SessionPlan, vehicle_id: str) -> None:
    """Refuse a Zenoh file that is not this vehicle's daemon's: a router's, or one whose client
    certificate names another role or vehicle (a router with access control silently drops every
    put, token and queryable of such a daemon: no alert would reach anyone). Raises ConfigError
    naming the file and the fix."""
    if plan.config_file is None:
        return
    where = f"--zenoh-config {plan.config_file}"
    if plan.mode == "router":
        raise ConfigError(
            f"{where} is a router's file (mode router): the daemon needs its own, e.g. "
            "DIR/daemon/zenoh.json5 of `roadgaze security init`"
        )
    name = certificate_name(zconf)
    expected = f"daemon.{vehicle_id}"
    if name is None or name == expected:
        return
    role = name.split(".", 1)[0]
    whose = {"consumer": "a consumer's", "speed": "the speed provider's", "router": "a router's"}
    owner = whose.get(role, f"certificate {name!r}'s")
    if role == "daemon":
        owner = f"the daemon file of vehicle {name.split('.', 1)[1]!r}"
    raise ConfigError(
        f"{where} is {owner} (its certificate is {name}, this daemon publishes as vehicle "
        f"{vehicle_id!r}): the router's access control would silently drop every alert, state "
        f"and liveliness token. Use the daemon's file of the same bundle (DIR/daemon/zenoh.json5 "
        f"of `roadgaze security init --vehicle-id {vehicle_id}`)"
    )


def unreachable_hint(plan: SessionPlan | None) -> str:
    """Why a client session may not have opened: nothing listens, or something listens but
    refused it (a TLS router reached over plain TCP, or a certificate it does not accept)."""
    endpoints = [] if plan is None else list(plan.connect)
    answering = [endpoint for endpoint in endpoints if endpoint_in_use(endpoint)]
    if not answering:
        return "is `roadgaze run` or a router up?"
    plain = [endpoint for endpoint in answering if endpoint.startswith("tcp/")]
    if plain:
        return (
            f"something listens at {', '.join(plain)} but refused the zenoh session: a router "
            "with TLS only (roadgaze security init) takes tls/ endpoints and a consumer's file: "
            "--zenoh-config DIR/consumer-NAME/zenoh.json5"
        )
    return (
        f"something listens at {', '.join(answering)} but refused the TLS session: a "
        "certificate from another CA, an expired one, or none (enable_mtls), or a router that "
        "is not a zenoh one; check the consumer's files of the same `roadgaze security init` "
        "bundle as the router's"
    )
