"""Transport: message schemas (pure), publisher and health sinks, the Zenoh link, the consumer."""

# The names are imported on first use (PEP 562): a consumer that needs only
# `roadgaze.transport.consumer` (or the message schemas) does not load the monitor and the link.

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
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
    from roadgaze.transport.support_message import SUPPORT_SCHEMA, SupportLevel, SupportMessage
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

_MODULE_OF = {
    "ALERT_SCHEMA": "roadgaze.transport.messages",
    "AlertCounts": "roadgaze.transport.link_state",
    "AlertMessage": "roadgaze.transport.messages",
    "BusPublisher": "roadgaze.transport.publisher",
    "DEFAULT_LISTEN": "roadgaze.transport.router",
    "EyeFields": "roadgaze.transport.messages",
    "Health": "roadgaze.transport.health",
    "Keys": "roadgaze.transport.keys",
    "LinkState": "roadgaze.transport.link_state",
    "MESSAGE_MAX_BYTES": "roadgaze.transport.payloads",
    "MESSAGE_MODELS": "roadgaze.transport.messages",
    "MessageLink": "roadgaze.transport.publisher",
    "MonitorSnapshot": "roadgaze.transport.messages",
    "PayloadError": "roadgaze.transport.payloads",
    "Router": "roadgaze.transport.router",
    "RouterSettings": "roadgaze.transport.router",
    "SPEED_MAX_BYTES": "roadgaze.transport.payloads",
    "SPEED_MAX_KMH": "roadgaze.transport.speed",
    "STATE_SCHEMA": "roadgaze.transport.messages",
    "SessionPlan": "roadgaze.transport.session",
    "SpeedInput": "roadgaze.transport.speed",
    "StateMessage": "roadgaze.transport.messages",
    "Subscription": "roadgaze.transport.subscription",
    "ThrottledWarning": "roadgaze.transport.throttle",
    "TransportStatus": "roadgaze.transport.messages",
    "VSS_PATHS": "roadgaze.transport.vss",
    "VssLink": "roadgaze.transport.vss",
    "VssPublisher": "roadgaze.transport.vss",
    "YAW_SCHEMA": "roadgaze.transport.messages",
    "YawMessage": "roadgaze.transport.messages",
    "ZenohLink": "roadgaze.transport.link",
    "build_zenoh_config": "roadgaze.transport.session",
    "endpoint_in_use": "roadgaze.transport.session",
    "insecure_endpoints": "roadgaze.transport.session",
    "json_schemas": "roadgaze.transport.messages",
    "open_session": "roadgaze.transport.session",
    "parse_json_object": "roadgaze.transport.payloads",
    "parse_json_value": "roadgaze.transport.payloads",
    "SUPPORT_SCHEMA": "roadgaze.transport.support_message",
    "SupportLevel": "roadgaze.transport.support_message",
    "SupportMessage": "roadgaze.transport.support_message",
    "parse_speed_kmh": "roadgaze.transport.speed",
    "parse_vss_text": "roadgaze.transport.vss",
    "plan_session": "roadgaze.transport.session",
    "printable": "roadgaze.transport.payloads",
    "router_config": "roadgaze.transport.router",
    "vss_key": "roadgaze.transport.vss",
    "vss_text": "roadgaze.transport.vss",
    "vss_values": "roadgaze.transport.vss",
    "zenoh_error_text": "roadgaze.transport.session",
}
"""Where each public name lives."""


def __getattr__(name: str) -> Any:
    module = _MODULE_OF.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


__all__ = [
    "ALERT_SCHEMA",
    "DEFAULT_LISTEN",
    "MESSAGE_MAX_BYTES",
    "MESSAGE_MODELS",
    "SPEED_MAX_BYTES",
    "SPEED_MAX_KMH",
    "STATE_SCHEMA",
    "SUPPORT_SCHEMA",
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
    "SupportLevel",
    "SupportMessage",
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
