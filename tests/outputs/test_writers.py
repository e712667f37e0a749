"""Writers: the flat record, JSONL and CSV, the yaw plot and the annotated video."""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from fakes import BLANK_FRAME, FACE, record_of
from roadgaze.errors import RoadgazeError
from roadgaze.outputs import (
    RECORD_FIELDS,
    AnnotatedVideoWriter,
    CsvWriter,
    JsonlWriter,
    YawPlot,
    annotate,
    record_fields,
)
from roadgaze.types import Alert, AlertKind, AlertLevel, Frame, PoseSample

WITH_FACE = PoseSample(0.5, 15, True, 20.25, 19.5, -3.0, 1.25, FACE, 1)
WITHOUT_FACE = PoseSample(0.0, 0, False, None, None, None, None, None, 0)


def test_record_fields_and_nulls() -> None:
    record = record_fields(record_of(WITH_FACE))
    assert record["t_s"] == 0.5 and record["frame"] == 15 and record["face"] is True
    assert (record["yaw_raw_deg"], record["yaw_deg"]) == (20.25, 19.5)
    assert (record["yaw_rate_dps"], record["yaw_std_deg"]) == (-3.0, 1.25)
    assert (record["x_left"], record["x_right"], record["x_center"]) == (100.0, 180.0, 150.0)
    empty = record_fields(record_of(WITHOUT_FACE))
    assert empty["face"] is False
    for key in ("yaw_raw_deg", "yaw_deg", "yaw_rate_dps", "yaw_std_deg", "x_left", "x_center"):
        assert empty[key] is None


ALERT = Alert(AlertKind.LONG_DISTRACTION, AlertLevel.WARNING, 0.5, 19.5, 3.0, 3.0)


def test_jsonl_one_object_per_line_with_the_verdict_and_alerts(tmp_path: Path) -> None:
    path = tmp_path / "sub" / "frames.jsonl"
    with JsonlWriter(path) as writer:
        writer.on_record(record_of(WITHOUT_FACE), BLANK_FRAME)
        writer.on_record(record_of(WITH_FACE, alerts=(ALERT,)), BLANK_FRAME)
    lines = path.read_text().splitlines()
    assert len(lines) == 2
    first, second = (json.loads(line) for line in lines)
    assert first["yaw_deg"] is None and first["on_road"] is True and first["alerts"] == []
    assert second["yaw_deg"] == 19.5 and second["gaze"] == "on_road"
    assert second["alerts"] == ["long_distraction:warning"]
    assert list(second) == list(RECORD_FIELDS)


def test_jsonl_to_a_stream_is_not_closed() -> None:
    stream = io.StringIO()
    writer = JsonlWriter(stream)
    writer.on_record(record_of(WITH_FACE), BLANK_FRAME)
    writer.close()
    assert json.loads(stream.getvalue())["frame"] == 15
    assert not stream.closed


def test_unwritable_output_is_one_clear_error(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("")
    with pytest.raises(RoadgazeError, match="cannot write frame records"):
        JsonlWriter(blocker / "frames.jsonl")


def test_csv_has_a_header_and_empty_cells_for_null(tmp_path: Path) -> None:
    path = tmp_path / "frames.csv"
    with CsvWriter(path) as writer:
        writer.on_record(record_of(WITHOUT_FACE), BLANK_FRAME)
        writer.on_record(record_of(WITH_FACE), BLANK_FRAME)
    rows = list(csv.DictReader(path.open()))
    assert len(rows) == 2
    assert rows[0]["yaw_deg"] == "" and rows[1]["yaw_deg"] == "19.5"
    assert rows[1]["x_center"] == "150.0"


def test_plot_is_a_png(tmp_path: Path) -> None:
    path = tmp_path / "yaw.png"
    with YawPlot(path) as plot:
        for i in range(20):
            sample = PoseSample(i / 10, i, True, float(i), float(i) - 0.5, 1.0, 1.0, FACE)
            plot.on_record(record_of(sample), BLANK_FRAME)
        plot.on_record(record_of(WITHOUT_FACE, alerts=(ALERT,)), BLANK_FRAME)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert cv2.imread(str(path)) is not None


def test_annotate_draws_lines_gauge_and_text_without_touching_the_input() -> None:
    image = np.zeros((240, 320, 3), np.uint8)
    drawn = annotate(image, record_of(WITH_FACE))
    assert not image.any()
    assert drawn.shape == image.shape
    # The centre line (green) crosses the face's middle row near the rotated x_center.
    middle = drawn[115]
    green = np.nonzero((middle[:, 1] > 200) & (middle[:, 0] < 50) & (middle[:, 2] < 50))[0]
    assert green.size > 0 and abs(float(green.mean()) - 150.0) < 15.0
    assert drawn[:60, 240:].any(), "gauge in the top-right corner"
    assert drawn[200:, :200].any(), "text at the bottom left"


def test_annotated_video_has_every_frame(tmp_path: Path) -> None:
    path = tmp_path / "annotated.mp4"
    with AnnotatedVideoWriter(path, fps=10.0) as writer:
        for i in range(8):
            sample = WITH_FACE if i % 2 else WITHOUT_FACE
            frame = Frame(i, i / 10, np.full((240, 320, 3), 40, np.uint8))
            writer.on_record(record_of(sample), frame)
    capture = cv2.VideoCapture(str(path))
    assert capture.get(cv2.CAP_PROP_FRAME_COUNT) == 8
    assert (capture.get(cv2.CAP_PROP_FRAME_WIDTH), capture.get(cv2.CAP_PROP_FRAME_HEIGHT)) == (
        320,
        240,
    )
    capture.release()
