"""A Zenoh router inside this process, for machines without `zenohd`.

`RouterSettings` names what the command line gives (listen endpoints, a Zenoh configuration
file); `router_config` turns them into a `zenoh.Config` in router mode; `Router` opens the session,
logs the endpoints it listens on and every session that connects or disconnects (Zenoh's
transport events), and closes it on exit. Defaults are safe: loopback only
(`tcp/127.0.0.1:7447`) and multicast scouting off, unless the file or the flags say otherwise.
"""

from __future__ import annotations

import json
import logging
import threading
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Self

from roadgaze.errors import TransportError
from roadgaze.transport.session import load_zenoh_file, zenoh_error_text
from roadgaze.types import ClosesOnExit

log = logging.getLogger("roadgaze.router")

DEFAULT_LISTEN = ("tcp/127.0.0.1:7447",)
"""Where the router listens when neither the flags nor a configuration file name an endpoint."""
SESSIONS_TRACKED_MAX = 4096
"""Open sessions whose address is remembered for the 'closed' line; beyond, only counted."""


@dataclass(frozen=True, slots=True)
class RouterSettings:
    """What `roadgaze router` was asked for."""

    listen: tuple[str, ...] = ()
    """Endpoints to listen on (`tcp/HOST:PORT`, `tls/HOST:PORT`, ...); they replace the file's.
    Empty: the file's endpoints, else `DEFAULT_LISTEN`."""
    config_file: Path | None = None
    """A Zenoh router configuration (JSON5, JSON or YAML), e.g. from `roadgaze security init`:
    TLS endpoints, mutual TLS, access control. Its mode must be `router` or unset."""


@dataclass(frozen=True, slots=True)
class RouterConfig:
    """The Zenoh configuration to open and the endpoints it listens on (for the log)."""

    zenoh_config: Any
    listen: tuple[str, ...]
    multicast_scouting: bool


def _endpoints(value: Any) -> tuple[str, ...]:
    """Zenoh's `listen/endpoints`: a list, or a per-mode table whose `router` entry applies."""
    if isinstance(value, dict):
        value = value.get("router", [])
    return tuple(str(endpoint) for endpoint in value or ())


def router_config(settings: RouterSettings) -> RouterConfig:
    """The router's `zenoh.Config`; raises TransportError for a missing or bad file, a file for
    another mode, or a bad endpoint."""
    import zenoh

    try:
        if settings.config_file is None:
            zconf = zenoh.Config()
            default_listen = _endpoints(json.loads(zconf.get_json("listen/endpoints")))
        else:
            path = settings.config_file
            default_listen = _endpoints(json.loads(zenoh.Config().get_json("listen/endpoints")))
            zconf = load_zenoh_file(path)
            mode = json.loads(zconf.get_json("mode"))
            if mode not in (None, "router"):
                raise TransportError(
                    f"zenoh config file {path} is for mode {mode}; roadgaze router needs a router "
                    "configuration (mode: 'router', or no mode)"
                )
        zconf.insert_json5("mode", json.dumps("router"))
        listen = settings.listen or _endpoints(json.loads(zconf.get_json("listen/endpoints")))
        if not settings.listen and listen == default_listen:
            listen = DEFAULT_LISTEN  # Zenoh's own default is every interface: not without asking
        zconf.insert_json5("listen/endpoints", json.dumps(list(listen)))
        multicast = json.loads(zconf.get_json("scouting/multicast/enabled"))
        if multicast is None:
            zconf.insert_json5("scouting/multicast/enabled", "false")
    except TransportError:
        raise
    except Exception as exc:  # zenoh's ZError for unreadable files, unknown keys, bad values
        where = f"zenoh config file {settings.config_file}" if settings.config_file else "settings"
        raise TransportError(f"bad router {where}: {zenoh_error_text(exc)}") from None
    return RouterConfig(zenoh_config=zconf, listen=listen, multicast_scouting=bool(multicast))


class Router(ClosesOnExit):
    """A Zenoh session in router mode, opened by `with`; logs sessions as they come and go.

    Raises TransportError on entry when an endpoint cannot be listened on (in use, unknown
    host or protocol, TLS files missing).
    """

    def __init__(self, settings: RouterSettings) -> None:
        self.settings = settings
        self.config = router_config(settings)  # bad settings fail here, before opening
        self._session: Any = None
        self._listener: Any = None
        self._lock = threading.Lock()
        self._open: dict[str, str] = {}
        self.sessions_opened = 0
        self.sessions_closed = 0

    @property
    def open_sessions(self) -> int:
        """Sessions (clients, peers, other routers) connected right now."""
        with self._lock:
            return self.sessions_opened - self.sessions_closed

    def __enter__(self) -> Self:
        import zenoh

        try:
            self._session = zenoh.open(self.config.zenoh_config)
        except Exception as exc:
            raise TransportError(
                f"cannot start the router on {', '.join(self.config.listen)}: "
                f"{zenoh_error_text(exc)}"
            ) from None
        try:
            # history: sessions that connected before the listener existed are reported too.
            self._listener = self._session.info.declare_transport_events_listener(
                self._on_transport_event, history=True
            )
        except BaseException:
            self.close()
            raise
        log.info(
            "zenoh router %s listening on %s (multicast scouting %s)",
            self._session.zid(),
            ", ".join(self.config.listen),
            "on" if self.config.multicast_scouting else "off",
            extra={"listen": list(self.config.listen), "zid": str(self._session.zid())},
        )
        return self

    def _describe(self, zid: str) -> str:
        """`from ADDRESS` (and `as NAME` with an authenticated link) of a session's links."""
        try:
            links = [link for link in self._session.info.links() if str(link.zid) == zid]
        except Exception as exc:
            log.debug("session links unavailable: %s", exc)
            return ""
        parts = [f"from {link.dst}" for link in links[:1]]
        names = sorted({str(link.auth_identifier) for link in links if link.auth_identifier})
        if names:
            parts.append(f"as {', '.join(names)}")
        return " ".join(parts)

    def _on_transport_event(self, event: Any) -> None:
        """Zenoh's callback thread: one log line per session opened or closed."""
        import zenoh

        transport = event.transport
        zid, kind = str(transport.zid), str(transport.whatami)
        if event.kind == zenoh.SampleKind.PUT:
            described = self._describe(zid)
            with self._lock:
                self.sessions_opened += 1
                if len(self._open) < SESSIONS_TRACKED_MAX:
                    self._open[zid] = described
                count = self.sessions_opened - self.sessions_closed
            log.info("session opened: %s %s %s (%d open)", kind, zid, described, count)
        else:
            with self._lock:
                self.sessions_closed += 1
                described = self._open.pop(zid, "")
                count = self.sessions_opened - self.sessions_closed
            log.info("session closed: %s %s %s (%d open)", kind, zid, described, count)

    def close(self) -> None:
        """Stop listening and close every session; idempotent."""
        listener, self._listener = self._listener, None
        session, self._session = self._session, None
        if listener is not None:
            try:
                listener.undeclare()
            except Exception as exc:
                log.debug("transport listener undeclare failed: %s", exc)
        if session is not None:
            try:
                session.close()
            except Exception as exc:
                log.debug("router session close failed: %s", exc)
            log.info(
                "zenoh router stopped (%d sessions served)",
                self.sessions_opened,
            )


ZENOH_LOG = "error,zenoh_link_tls=warn"
"""Zenoh's own log in `roadgaze router`: errors, and the TLS link's warnings, which name each
refused handshake (a plain TCP client, no or a foreign certificate). `RUST_LOG` replaces it."""


def log_refused_handshakes() -> None:
    """Turn on Zenoh's own log for refused TLS handshakes (Zenoh opens no transport for them, so
    the transport events never see them), relayed to stderr through roadgaze's log
    (`roadgaze.transport.zenoh_log`: Zenoh itself writes to stdout, in colour). Once per
    process."""
    import zenoh

    from roadgaze.transport.zenoh_log import relay_zenoh_log

    relay_zenoh_log()
    try:
        zenoh.init_log_from_env_or(ZENOH_LOG)
    except Exception as exc:  # already initialised in this process
        log.debug("zenoh log not initialised: %s", exc)
