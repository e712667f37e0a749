"""The typed description of the flat record: every field `record_fields` returns is described,
with the type its values have, so columnar writers derived from it lose nothing."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest

from fakes import FACE, record_of
from roadgaze.outputs import (
    ALERT_SCHEMA,
    RECORD_FIELDS,
    RECORD_SCHEMA,
    FieldType,
    alert_fields,
    record_fields,
)
from roadgaze.outputs.records import HAND_SCHEMA
from roadgaze.transport import AlertMessage
from roadgaze.types import (
    Alert,
    AlertKind,
    AlertLevel,
    Hand,
    HandSide,
    PhoneJudgement,
    PhonePose,
    PoseSample,
)

ALERTS = (
    Alert(AlertKind.LONG_DISTRACTION, AlertLevel.WARNING, 0.5, 19.5, 3.0, 3.0),
    Alert(
        AlertKind.CLEARED,
        AlertLevel.INFO,
        4.0,
        None,
        3.5,
        3.5,
        unavailable_s=0.25,
        speed_kmh=57.0,
        clears=(AlertKind.LONG_DISTRACTION, AlertKind.VATS),
    ),
)
HAND = Hand(
    HandSide.RIGHT,
    0.97,
    0.91,
    np.full((21, 3), 100.0, np.float32),
    (90.0, 80.0, 130.0, 150.0),
)
PHONE = PhoneJudgement(True, 0.82, HandSide.RIGHT, PhonePose.EAR)
RECORDS = (
    record_of(PoseSample(0.5, 15, True, 20.25, 19.5, -3.0, 1.25, FACE, 1), alerts=ALERTS),
    record_of(PoseSample(0.0, 0, False, None, None, None, None, None, 0)),
    record_of(
        PoseSample(1.0, 30, False, None, None, None, None, None, 0, hands=(HAND,), phone=PHONE)
    ),
)


def has_type(value: Any, field_type: FieldType) -> bool:
    if value is None:
        return True
    if field_type is FieldType.STR_LIST:
        return isinstance(value, list) and all(isinstance(item, str) for item in value)
    if field_type is FieldType.HANDS:
        return isinstance(value, list) and all(isinstance(item, dict) for item in value)
    if field_type is FieldType.INT:
        return isinstance(value, int) and not isinstance(value, bool)
    if field_type is FieldType.FLOAT:
        return isinstance(value, float)
    expected = {FieldType.BOOL: bool, FieldType.STR: str}[field_type]
    return isinstance(value, expected)


@pytest.mark.parametrize("record", RECORDS, ids=["face-and-alerts", "no-face", "hands"])
def test_every_field_of_the_flat_record_is_described_with_its_type(record: Any) -> None:
    fields = record_fields(record)
    undescribed = [name for name in fields if name not in RECORD_FIELDS]
    assert undescribed == [], "add these fields to RECORD_SCHEMA in outputs/records.py"
    assert tuple(fields) == RECORD_FIELDS
    wrong = {
        name: (fields[name], field_type.value)
        for name, field_type in RECORD_SCHEMA
        if not has_type(fields[name], field_type)
    }
    assert wrong == {}


def test_the_described_types_are_what_a_face_frame_holds() -> None:
    fields = record_fields(RECORDS[0])
    assert fields["alerts"] == ["long_distraction:warning", "cleared:info"]
    assert fields["gaze"] in {"on_road", "off_road", "unknown"}
    assert all(fields[name] is not None for name in ("t_s", "frame", "face", "x_left", "quality"))


@pytest.mark.parametrize("alert", ALERTS, ids=lambda a: a.kind.value)
def test_alert_fields_are_the_alert_message_without_its_wire_fields(alert: Alert) -> None:
    fields = alert_fields(alert)
    assert tuple(fields) == tuple(name for name, _ in ALERT_SCHEMA)
    assert all(has_type(fields[name], field_type) for name, field_type in ALERT_SCHEMA)
    message = AlertMessage.from_alert(alert, "car-0", 0, 0.0).model_dump(mode="json")
    wire_only = {"schema_id", "vehicle_id", "seq", "wall_time"}
    assert set(message) - wire_only == set(fields)
    assert {name: message[name] for name in fields} == fields


def test_durations_are_floats_from_frame_0_even_when_the_monitor_gives_an_int() -> None:
    """A window that sums no glance yet is `sum([]) == 0`, an int: the record still says 0.0."""
    first = record_of(PoseSample(0.0, 0, True, 1.0, 1.0, 0.0, 1.0, FACE, 1))
    verdict = dataclasses.replace(first.verdict, window_off_road_s=0, off_road_s=0)
    fields = record_fields(record_of(first.sample, verdict))
    assert type(fields["window_off_road_s"]) is float and fields["window_off_road_s"] == 0.0
    assert type(fields["off_road_s"]) is float


def test_the_hands_and_the_phone_judgement_in_the_record() -> None:
    fields = record_fields(RECORDS[2])
    assert fields["n_hands"] == 1
    assert (fields["hand_right_score"], fields["hand_right_x"], fields["hand_right_y"]) == (
        0.91,
        110.0,
        115.0,
    )
    assert fields["hand_left_score"] is None
    assert (fields["phone_use"], fields["phone_score"]) == (True, 0.82)
    assert (fields["phone_hand"], fields["phone_pose"]) == ("right", "ear")
    off = record_fields(RECORDS[1])  # the hand stage off: every hand field null
    assert all(off[name] is None for name, _ in HAND_SCHEMA)


def test_the_record_carries_forward_and_lane_support_and_writes_them_as_csv(
    tmp_path: Any,
) -> None:
    import csv

    from fakes import eyes_of
    from roadgaze.config import MonitorConfig
    from roadgaze.monitor import Monitor
    from roadgaze.outputs import CsvWriter
    from roadgaze.outputs.records import alert_row, record_fields
    from roadgaze.types import FrameRecord

    monitor = Monitor(MonitorConfig(neutral_yaw_deg=0.0))
    records = []
    for frame in range(75):  # 3 s ahead, then 2 s at the left mirror, at 15 fps and 70 km/h
        t_s = frame / 15
        yaw_deg = 35.0 if t_s >= 3.0 - 1e-9 else 0.0
        sample = PoseSample(t_s, frame, True, yaw_deg, yaw_deg, 0.0, 1.0, eyes=eyes_of())
        alerts = monitor.update(sample, 70.0)
        records.append(FrameRecord(sample, monitor.verdict, alerts))
    fields = [record_fields(r) for r in records]
    levels = [(f["support_forward"], f["support_lane"]) for f in fields]
    assert levels[29] == ("heightened", "heightened")  # not yet watched the road 2 s
    assert levels[30] == levels[44] == ("normal", "normal")  # 2.0 s
    assert levels[45] == ("heightened", "heightened")  # 3.0 s: the mirror look's first frame
    verdict = dataclasses.replace(records[0].verdict, outputs=())
    assert record_fields(dataclasses.replace(records[0], verdict=verdict))["support_lane"] is None
    path = tmp_path / "drive.csv"
    with CsvWriter(path) as writer:
        for record in records:
            writer.on_record(record, None)  # type: ignore[arg-type]
    with path.open(newline="", encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle))
    assert [row["support_forward"] for row in rows] == [level for level, _ in levels]
    assert [row["support_lane"] for row in rows] == [level for _, level in levels]
    assert alert_row(ALERTS[0])["support_forward"] is None  # an alert of its own: no frame
