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
    EyeFields,
    MonitorSnapshot,
    StateMessage,
    TransportStatus,
    YawMessage,
    json_schemas,
)
from roadgaze.transport.publisher import BusPublisher, MessageLink
from roadgaze.transport.session import (
    build_zenoh_config,
    open_session,
    session_config_dict,
    zenoh_error_text,
)
from roadgaze.transport.speed import SpeedInput, parse_speed_kmh
from roadgaze.transport.vss import (
    VSS_PATHS,
    VssLink,
    VssPublisher,
    vss_key,
    vss_text,
    vss_values,
)

__all__ = [
    "ALERT_SCHEMA",
    "MESSAGE_MODELS",
    "STATE_SCHEMA",
    "VSS_PATHS",
    "YAW_SCHEMA",
    "AlertMessage",
    "BusPublisher",
    "EyeFields",
    "Health",
    "Keys",
    "MessageLink",
    "MonitorSnapshot",
    "SpeedInput",
    "StateMessage",
    "TransportStatus",
    "VssLink",
    "VssPublisher",
    "YawMessage",
    "ZenohLink",
    "build_zenoh_config",
    "json_schemas",
    "open_session",
    "parse_speed_kmh",
    "session_config_dict",
    "vss_key",
    "vss_text",
    "vss_values",
    "zenoh_error_text",
]
