"""Transport: the message schemas (pure), the publisher and health sinks, and the Zenoh link."""

from roadgaze.transport.health import Health
from roadgaze.transport.keys import Keys
from roadgaze.transport.link import ZenohLink
from roadgaze.transport.link_state import AlertCounts, LinkState
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
from roadgaze.transport.payloads import (
    MESSAGE_MAX_BYTES,
    SPEED_MAX_BYTES,
    PayloadError,
    parse_json_object,
    parse_json_value,
    printable,
)
from roadgaze.transport.publisher import BusPublisher, MessageLink
from roadgaze.transport.router import DEFAULT_LISTEN, Router, RouterSettings, router_config
from roadgaze.transport.session import (
    SessionPlan,
    build_zenoh_config,
    endpoint_in_use,
    insecure_endpoints,
    open_session,
    plan_session,
    zenoh_error_text,
)
from roadgaze.transport.speed import SPEED_MAX_KMH, SpeedInput, parse_speed_kmh
from roadgaze.transport.subscription import Subscription
from roadgaze.transport.throttle import ThrottledWarning
from roadgaze.transport.vss import (
    VSS_PATHS,
    VssLink,
    VssPublisher,
    parse_vss_text,
    vss_key,
    vss_text,
    vss_values,
)

__all__ = [
    "ALERT_SCHEMA",
    "DEFAULT_LISTEN",
    "MESSAGE_MAX_BYTES",
    "MESSAGE_MODELS",
    "SPEED_MAX_BYTES",
    "SPEED_MAX_KMH",
    "STATE_SCHEMA",
    "VSS_PATHS",
    "YAW_SCHEMA",
    "AlertCounts",
    "AlertMessage",
    "BusPublisher",
    "EyeFields",
    "Health",
    "Keys",
    "LinkState",
    "MessageLink",
    "MonitorSnapshot",
    "PayloadError",
    "Router",
    "RouterSettings",
    "SessionPlan",
    "SpeedInput",
    "StateMessage",
    "Subscription",
    "ThrottledWarning",
    "TransportStatus",
    "VssLink",
    "VssPublisher",
    "YawMessage",
    "ZenohLink",
    "build_zenoh_config",
    "endpoint_in_use",
    "insecure_endpoints",
    "json_schemas",
    "open_session",
    "parse_json_object",
    "parse_json_value",
    "parse_speed_kmh",
    "parse_vss_text",
    "plan_session",
    "printable",
    "router_config",
    "vss_key",
    "vss_text",
    "vss_values",
    "zenoh_error_text",
]
