"""The live view: the recorder's channels served with Foxglove's WebSocket protocol.

`run --foxglove [HOST:]PORT` starts foxglove-sdk's server (subprotocol `foxglove.websocket.v1`)
on the recorder's context: a client (the Foxglove app, `docs/foxglove.md`) is told the channels
(`advertise`), subscribes to those it shows and receives each message as it is logged. Camera
frames are encoded only while a client is subscribed to them. The server binds to loopback
unless told otherwise; bound elsewhere it warns, since the stream shows the driver's face.

The SDK logs one error line per bad frame a client sends (a hostile client made 36,150 in
45 s): a `ClientLogThrottle` lets, per client host, the first line through at once and then
one per 10 s saying how many were held back; the count still held back is logged when the
server stops.
"""

from __future__ import annotations

import ipaddress
import logging
import re
import threading

import foxglove
from foxglove.websocket import ChannelView, Client, ServerListener, WebSocketServer

from roadgaze.errors import ConfigError
from roadgaze.outputs.foxglove.channels import TOPIC_IMAGE
from roadgaze.transport.throttle import KeyedThrottle

log = logging.getLogger(__name__)

DEFAULT_HOST = "127.0.0.1"
SERVER_NAME = "roadgaze"


def parse_address(text: str) -> tuple[str, int]:
    """`[HOST:]PORT` (an IPv6 host in brackets: `[::1]:8765`) as (host, port); loopback when no
    host is given. Raises `ConfigError` for anything else."""
    spec = text.strip()
    host, port_text = DEFAULT_HOST, spec
    if spec.startswith("["):
        inside, bracket, rest = spec[1:].partition("]")
        if not bracket or not rest.startswith(":"):
            raise ConfigError(f"--foxglove {text!r}: expected [HOST:]PORT, e.g. 8765 or [::1]:8765")
        host, port_text = inside, rest[1:]
    elif ":" in spec:
        host, _, port_text = spec.rpartition(":")
    if not port_text.isdigit() or not 0 <= int(port_text) <= 65535 or not host:
        raise ConfigError(
            f"--foxglove {text!r}: expected [HOST:]PORT with a port 0-65535, e.g. 8765 or "
            "127.0.0.1:8765"
        )
    return host, int(port_text)


def is_loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


CLIENT_LOGGERS = ("foxglove.websocket.connected_client", "foxglove.websocket.server")
"""The SDK's loggers that write a line per message (or connection) of a client."""
_CLIENT_ADDRESS = re.compile(r"(?P<host>\[[0-9A-Fa-f:.]+\]|\d{1,3}(?:\.\d{1,3}){3}):\d+")


class ClientLogThrottle(logging.Filter):
    """A filter on the SDK's client loggers: per client host (the address in the line), the
    first warning or error at once, then at most one per `period_s` with how many were held
    back. Lines that name no client, and debug lines, pass unchanged."""

    def __init__(self, period_s: float = 10.0) -> None:
        super().__init__()
        self.throttle = KeyedThrottle(period_s)

    def filter(self, record: logging.LogRecord) -> bool:
        if record.levelno < logging.WARNING:
            return True
        text = record.getMessage()
        found = _CLIENT_ADDRESS.search(text)
        if found is None:
            return True
        client = found.group("host")
        passed = self.throttle(client)
        if passed is None:
            return False
        held_back, total = passed
        if held_back:
            record.msg = (
                f"{text} ({held_back} more lines about client {client} held back since the "
                f"last, {total} in all)"
            )
            record.args = ()
        return True

    def report(self) -> None:
        """Log how many lines about each client are still held back (at the server's stop)."""
        for client, (held_back, total) in self.throttle.held_back().items():
            log.warning(
                "foxglove: %d more lines about client %s held back (%d in all: bad frames from it)",
                held_back,
                client,
                total,
            )


class _Subscriptions(ServerListener):
    """The server's listener: how many clients are subscribed to the camera frames."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self.images = 0
        self.clients: set[int] = set()

    def on_subscribe(self, client: Client, channel: ChannelView) -> None:
        with self._lock:
            self.clients.add(client.id)
            self.images += channel.topic == TOPIC_IMAGE
        log.info("foxglove: client %s subscribed to %s", client.id, channel.topic)

    def on_unsubscribe(self, client: Client, channel: ChannelView) -> None:
        with self._lock:
            self.images -= channel.topic == TOPIC_IMAGE
            self.images = max(0, self.images)


class LiveServer:
    """A `Target` of the recorder: the Foxglove WebSocket server on `host:port` (port 0: any
    free one; `port` tells which)."""

    def __init__(self, host: str, port: int, images: bool) -> None:
        self.host = host
        self.requested_port = port
        self.images = images
        self._subscriptions = _Subscriptions()
        self._server: WebSocketServer | None = None
        self.client_logs = ClientLogThrottle()

    @property
    def port(self) -> int:
        return self.requested_port if self._server is None else self._server.port

    @property
    def url(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"ws://{host}:{self.port}"

    def open(self, context: foxglove.Context) -> None:
        for name in CLIENT_LOGGERS:
            logging.getLogger(name).addFilter(self.client_logs)
        try:
            self._server = foxglove.start_server(
                name=SERVER_NAME,
                host=self.host,
                port=self.requested_port,
                context=context,
                server_listener=self._subscriptions,
                channel_filter=None
                if self.images
                else (lambda channel: channel.topic != TOPIC_IMAGE),
            )
        except (OSError, RuntimeError) as exc:
            self._stop_filtering()
            raise ConfigError(
                f"cannot serve the Foxglove live view on {self.host}:{self.requested_port}: {exc}"
            ) from None
        log.info(
            "foxglove: live view on %s (Foxglove app: Open connection, Foxglove WebSocket)",
            self.url,
        )
        if not is_loopback(self.host):
            log.warning(
                "foxglove: the live view on %s is reachable from the network and streams the "
                "driver's face%s; bind it to 127.0.0.1 (the default) unless the network is trusted",
                self.url,
                "" if self.images else " (images off: records and annotations only)",
            )

    def images_wanted(self) -> bool:
        return self.images and self._subscriptions.images > 0

    def describe(self, metadata: object) -> None:
        return None

    def tick(self, now_s: float) -> None:
        return None

    def close(self) -> None:
        server, self._server = self._server, None
        if server is not None:
            server.stop()
            self._stop_filtering()
            self.client_logs.report()

    def _stop_filtering(self) -> None:
        for name in CLIENT_LOGGERS:
            logging.getLogger(name).removeFilter(self.client_logs)
