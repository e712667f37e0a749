"""The Foxglove layout shipped as `docs/foxglove-layout.json`: the camera image with the face's
annotations, yaw / pitch / gaze against the road zone, the timers against their thresholds, the
zone, gaze, eyes and an ambiguous driver over time, the alerts, the state, the driver chosen on
each camera frame and the log.

Each panel's settings are built with foxglove-sdk's typed layout classes (`foxglove.layouts`, so
their names are the app's), and the whole is written in the layout format the Foxglove app and
Lichtblick import (Layouts > Import from file): `configById` keyed `TYPE!ID`, and a `layout` tree
of row and column splits. `python -m roadgaze.outputs.foxglove.layout` prints it; a test checks
that the shipped file is what this prints and that every topic it names is a recorded channel.
"""

from __future__ import annotations

import json
from typing import Any

import foxglove.layouts as fl

from roadgaze.outputs.foxglove.channels import (
    TOPIC_ALERTS,
    TOPIC_ANNOTATIONS,
    TOPIC_DRIVER,
    TOPIC_IMAGE,
    TOPIC_LIMITS,
    TOPIC_LOG,
    TOPIC_RECORD,
    TOPIC_STATE,
    TOPIC_SUPPORT,
)

APP_PANEL_TYPES = {"Log": "RosOut"}
"""foxglove-sdk's panel types whose id in the app's layout format differs."""

ROAD = "#2ca02c"
LIMIT_STYLE: dict[str, Any] = {"color": ROAD, "line_style": "dashed", "line_size": 1.0}


def _series(topic: str, field: str, label: str, **style: Any) -> fl.PlotSeries:
    return fl.PlotSeries(
        value=f"{topic}.{field}", label=label, enabled=True, timestamp_method="receiveTime", **style
    )


def _plot(title: str, paths: list[fl.PlotSeries], y_label: str) -> fl.PlotPanel:
    config = fl.PlotConfig(
        paths=paths, show_legend=True, legend_display="top", is_synced=True, y_axis_label=y_label
    )
    return fl.PlotPanel(title=title, config=config)


def panels() -> dict[str, fl.BasePanel]:
    """The panels by their id in the layout."""
    image = fl.ImagePanel(
        title="driver camera",
        config=fl.ImageConfig(
            synchronize=True,
            image_mode=fl.ImageModeConfig(
                image_topic=TOPIC_IMAGE,
                annotations={TOPIC_ANNOTATIONS: fl.ImageAnnotationSettings(visible=True)},
            ),
        ),
    )
    yaw = _plot(
        "yaw (deg, + = driver's left) against the road zone",
        [
            _series(TOPIC_RECORD, "yaw_deg", "yaw (smoothed)", color="#1f77b4"),
            _series(TOPIC_RECORD, "yaw_raw_deg", "yaw (raw)", color="#7f7f7f", show_line=False),
            _series(TOPIC_RECORD, "gaze_yaw_deg", "gaze (head + eyes)", color="#17becf"),
            _series(TOPIC_RECORD, "neutral_yaw_deg", "learned neutral", color=ROAD),
            _series(TOPIC_LIMITS, "yaw_min_deg", "road zone", **LIMIT_STYLE),
            _series(TOPIC_LIMITS, "yaw_max_deg", "road zone", **LIMIT_STYLE),
        ],
        "deg",
    )
    pitch = _plot(
        "pitch (deg, + = up) against the road zone",
        [
            _series(TOPIC_RECORD, "pitch_deg", "pitch (smoothed)", color="#9467bd"),
            _series(TOPIC_RECORD, "gaze_pitch_deg", "gaze (head + eyes)", color="#17becf"),
            _series(TOPIC_RECORD, "neutral_pitch_deg", "learned neutral", color=ROAD),
            _series(TOPIC_LIMITS, "pitch_min_deg", "road zone", **LIMIT_STYLE),
            _series(TOPIC_LIMITS, "pitch_max_deg", "road zone", **LIMIT_STYLE),
        ],
        "deg",
    )
    threshold = {"line_style": "dotted", "line_size": 1.0}
    timers = _plot(
        "timers (s) against their thresholds",
        [
            _series(TOPIC_RECORD, "off_road_s", "off road, this glance", color="#d62728"),
            _series(TOPIC_RECORD, "distraction_s", "distraction", color="#ff7f0e"),
            _series(
                TOPIC_RECORD, "window_off_road_s", "off road in the VATS window", color="#9467bd"
            ),
            _series(TOPIC_RECORD, "closure_s", "eyes closed", color="#8c564b"),
            _series(
                TOPIC_LIMITS, "long_distraction_s", "long distraction", color="#ff7f0e", **threshold
            ),
            _series(TOPIC_LIMITS, "vats_threshold_s", "VATS", color="#9467bd", **threshold),
        ],
        "s",
    )
    states = fl.StateTransitionsPanel(
        title="zone, gaze, eyes",
        config=fl.StateTransitionsConfig(
            is_synced=True,
            paths=[
                fl.StateTransitionsSeries(
                    value=f"{TOPIC_RECORD}.{field}", label=field, timestamp_method="receiveTime"
                )
                for field in (
                    "zone",
                    "gaze",
                    "eyes",
                    "eyes_on_road",
                    "driver_ambiguous",
                    "support_forward",
                    "support_lane",
                )
            ],
        ),
    )
    alerts = fl.RawMessagesPanel(
        title="alerts", config=fl.RawMessagesConfig(topic_path=TOPIC_ALERTS)
    )
    state = fl.RawMessagesPanel(title="state", config=fl.RawMessagesConfig(topic_path=TOPIC_STATE))
    driver = fl.RawMessagesPanel(
        title="driver", config=fl.RawMessagesConfig(topic_path=TOPIC_DRIVER)
    )
    support = fl.RawMessagesPanel(
        title="support", config=fl.RawMessagesConfig(topic_path=TOPIC_SUPPORT)
    )
    log = fl.LogPanel(title="log", config=fl.LogConfig(topic_to_render=TOPIC_LOG))
    return {
        "image": image,
        "yaw": yaw,
        "pitch": pitch,
        "timers": timers,
        "states": states,
        "alerts": alerts,
        "state": state,
        "driver": driver,
        "support": support,
        "log": log,
    }


def _split(direction: str, first: Any, second: Any, percentage: float) -> dict[str, Any]:
    return {"direction": direction, "first": first, "second": second, "splitPercentage": percentage}


def layout() -> dict[str, Any]:
    """The layout in the app's import format."""
    config_by_id: dict[str, Any] = {}
    keys: dict[str, str] = {}
    for name, panel in panels().items():
        entry = json.loads(panel.to_json())
        panel_type = APP_PANEL_TYPES.get(entry["panelType"], entry["panelType"])
        key = f"{panel_type}!roadgaze-{name}"
        config = dict(entry.get("config", {}))
        if "title" in entry:
            config["foxglovePanelTitle"] = entry["title"]
        config_by_id[key] = config
        keys[name] = key
    left = _split("column", keys["image"], keys["states"], 70)
    driver = _split("column", keys["driver"], keys["support"], 50)
    state = _split("column", keys["state"], driver, 70)
    bottom = _split("row", keys["alerts"], _split("row", state, keys["log"], 50), 34)
    right = _split(
        "column",
        keys["yaw"],
        _split("column", keys["pitch"], _split("column", keys["timers"], bottom, 45), 35),
        27,
    )
    return {
        "configById": config_by_id,
        "globalVariables": {},
        "userNodes": {},
        "playbackConfig": {"speed": 1},
        "layout": _split("row", left, right, 45),
    }


def layout_json() -> str:
    """The shipped file's text."""
    return json.dumps(layout(), indent=2, sort_keys=True) + "\n"


def topics_named(node: Any) -> set[str]:
    """Every topic a layout names (in image topics, annotation keys, message paths)."""
    found: set[str] = set()
    if isinstance(node, dict):
        for key, value in node.items():
            if isinstance(key, str) and key.startswith("/"):
                found.add(key)
            found |= topics_named(value)
    elif isinstance(node, list):
        for value in node:
            found |= topics_named(value)
    elif isinstance(node, str) and node.startswith("/"):
        found.add(node.split(".", 1)[0])
    return found


if __name__ == "__main__":
    print(layout_json(), end="")
