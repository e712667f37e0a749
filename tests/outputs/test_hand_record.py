"""Each hand in the record: its side, scores and 21 landmarks (to 0.1 px) in the JSON lines and
the MCAP record, typed by the record's schema; no CSV column (a cell holds one value); null while
the hand stage is off."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import jsonschema
import numpy as np
import pytest

from fakes import BLANK_FRAME, record_of
from roadgaze.outputs import CsvWriter, JsonlWriter, record_fields
from roadgaze.outputs.foxglove.channels import record_json_schema
from roadgaze.outputs.hand_record import HAND_SCHEMA, hand_landmarks
from roadgaze.outputs.records import CSV_FIELDS, alert_row
from roadgaze.types import (
    Alert,
    AlertKind,
    AlertLevel,
    FrameRecord,
    Hand,
    HandSide,
    PhoneJudgement,
    PhonePose,
    PoseSample,
)

LANDMARKS = np.column_stack(
    (200.04 + np.arange(21), 150.26 - 2 * np.arange(21), np.linspace(-3.0, -0.01, 21))
).astype(np.float32)
HAND = Hand(HandSide.RIGHT, 0.9712, 0.9134, LANDMARKS, (200.0, 110.0, 220.0, 150.3))
PHONE = PhoneJudgement(True, 0.82, HandSide.RIGHT, PhonePose.HELD_UP)


def frame_record(hands: tuple[Hand, ...] | None, phone: PhoneJudgement | None) -> FrameRecord:
    sample = PoseSample(1.0, 30, False, None, None, None, None, None, 0, hands=hands, phone=phone)
    return record_of(sample)


def test_each_hand_with_its_side_scores_and_landmarks_to_a_tenth_of_a_pixel() -> None:
    fields = record_fields(frame_record((HAND,), PHONE))
    [hand] = fields["hands"]
    assert (hand["side"], hand["side_score"], hand["score"]) == ("right", 0.971, 0.913)
    assert len(hand["landmarks_px"]) == 21
    assert hand["landmarks_px"][0] == [200.0, 150.3, -3.0]
    assert hand["landmarks_px"][20] == [220.0, 110.3, 0.0]
    assert math.copysign(1.0, hand["landmarks_px"][20][2]) == 1.0  # not -0.0
    expected = np.round(LANDMARKS.astype(np.float64), 1)
    assert np.abs(np.asarray(hand["landmarks_px"]) - LANDMARKS).max() <= 0.05 + 1e-4
    assert np.asarray(hand["landmarks_px"]).tolist() == expected.tolist()
    assert record_fields(frame_record((), PhoneJudgement(False, 0.1)))["hands"] == []
    assert record_fields(frame_record(None, None))["hands"] is None  # the stage off
    broken = Hand(HandSide.LEFT, 0.5, 0.6, np.full((21, 3), np.nan, np.float32), HAND.box_px)
    assert hand_landmarks(broken)["landmarks_px"] is None
    assert HAND_SCHEMA[-1][0] == "hands"


def test_the_json_lines_carry_the_hands_and_the_csv_keeps_its_flat_columns(
    tmp_path: Path,
) -> None:
    records = [frame_record((HAND,), PHONE), frame_record(None, None)]
    alert = Alert(AlertKind.PHONE_USE, AlertLevel.WARNING, 1.5, None, 0.0, 0.0)
    with JsonlWriter(tmp_path / "r.jsonl") as jsonl, CsvWriter(tmp_path / "r.csv") as table:
        for writer in (jsonl, table):
            for record in records:
                writer.on_record(record, BLANK_FRAME)
            writer.on_alert(alert)
    rows = [json.loads(line) for line in (tmp_path / "r.jsonl").read_text().splitlines()]
    assert [row["hands"] is None for row in rows] == [False, True, True]
    assert rows[0]["hands"][0]["landmarks_px"][0] == [200.0, 150.3, -3.0]
    with (tmp_path / "r.csv").open(newline="", encoding="utf-8") as handle:
        reader = csv.DictReader(handle)
        cells = list(reader)
    assert tuple(reader.fieldnames or ()) == CSV_FIELDS and "hands" not in CSV_FIELDS
    assert [row["hand_right_score"] for row in cells] == ["0.913", "", ""]
    assert alert_row(alert)["hands"] is None


def test_the_mcap_record_schema_types_the_hands() -> None:
    schema = record_json_schema()
    for record in (frame_record((HAND,), PHONE), frame_record(None, None)):
        jsonschema.validate(record_fields(record), schema)
    wrong = record_fields(frame_record((HAND,), PHONE))
    wrong["hands"][0]["landmarks_px"][3] = [1.0, 2.0]
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(wrong, schema)
