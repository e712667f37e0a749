"""Zenoh session configuration from roadgaze's settings, and a plain session for tools."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from roadgaze.config import ZenohConfig
from roadgaze.errors import TransportError


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
