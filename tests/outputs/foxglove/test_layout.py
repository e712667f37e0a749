"""The shipped Foxglove layout (docs/foxglove-layout.json): what the code builds, in the app's
import format, naming only recorded channels and fields."""

from __future__ import annotations

import json
import re

from repo_paths import REPO
from roadgaze.config import MonitorConfig
from roadgaze.outputs import RECORD_FIELDS
from roadgaze.outputs.foxglove.channels import (
    TOPIC_LIMITS,
    TOPIC_RECORD,
    TOPICS,
    limits_json_schema,
)
from roadgaze.outputs.foxglove.layout import layout, layout_json, topics_named

SHIPPED = REPO / "docs" / "foxglove-layout.json"
APP_PANELS = {"Image", "Plot", "StateTransitions", "RawMessages", "RosOut"}


def test_the_shipped_layout_is_what_the_code_builds() -> None:
    assert SHIPPED.read_text(encoding="utf-8") == layout_json(), (
        "regenerate: python -m roadgaze.outputs.foxglove.layout > docs/foxglove-layout.json"
    )


def test_it_is_in_the_apps_import_format_with_every_panel_placed() -> None:
    document = json.loads(SHIPPED.read_text(encoding="utf-8"))
    assert set(document) == {
        "configById",
        "globalVariables",
        "userNodes",
        "playbackConfig",
        "layout",
    }
    placed: list[str] = []

    def walk(node: object) -> None:
        if isinstance(node, str):
            placed.append(node)
            return
        assert isinstance(node, dict) and node["direction"] in ("row", "column")
        assert 0 < node["splitPercentage"] < 100
        walk(node["first"])
        walk(node["second"])

    walk(document["layout"])
    assert sorted(placed) == sorted(document["configById"])
    assert {key.split("!")[0] for key in placed} == APP_PANELS


def test_it_names_only_recorded_channels_and_fields() -> None:
    document = layout()
    assert topics_named(document) == set(TOPICS)
    paths = re.findall(r'"(/[a-z_/]+)\.([a-z_]+)"', json.dumps(document))
    fields = {
        TOPIC_RECORD: set(RECORD_FIELDS),
        TOPIC_LIMITS: set(limits_json_schema(MonitorConfig())["properties"]),
    }
    assert paths
    for topic, field in paths:
        assert field in fields[topic], f"{topic}.{field}"
    image = document["configById"]["Image!roadgaze-image"]
    assert image["imageMode"]["imageTopic"] == "/camera/image"
    assert image["imageMode"]["annotations"] == {"/roadgaze/annotations": {"visible": True}}
