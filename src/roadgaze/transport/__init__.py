"""Transport: the message schemas (pure), the publisher and health sinks, and the Zenoh link."""

from roadgaze.transport.health import Health
from roadgaze.transport.keys import Keys
from roadgaze.transport.link import ZenohLink
from roadgaze.transport.messages import (
    ALERT_SCHEMA,
    MESSAGE_MODELS,
    STATE_SCHEMA,
    YAW_SCHEMA,
    AlertMessage,
    MonitorSnapshot,
    StateMessage,
    TransportStatus,
    YawMessage,
    json_schemas,
)
from roadgaze.transport.publisher import BusPublisher, MessageLink
from roadgaze.transport.router import DEFAULT_LISTEN, Router, RouterSettings, router_config
from roadgaze.transport.session import (
    build_zenoh_config,
    open_session,
    session_config_dict,
    zenoh_error_text,
)
from roadgaze.transport.speed import SpeedInput, parse_speed_kmh

__all__ = [
    "ALERT_SCHEMA",
    "DEFAULT_LISTEN",
    "MESSAGE_MODELS",
    "STATE_SCHEMA",
    "YAW_SCHEMA",
    "AlertMessage",
    "BusPublisher",
    "Health",
    "Keys",
    "MessageLink",
    "MonitorSnapshot",
    "Router",
    "RouterSettings",
    "SpeedInput",
    "StateMessage",
    "TransportStatus",
    "YawMessage",
    "ZenohLink",
    "build_zenoh_config",
    "json_schemas",
    "open_session",
    "parse_speed_kmh",
    "router_config",
    "session_config_dict",
    "zenoh_error_text",
]
