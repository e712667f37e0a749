"""Writers: JSONL and CSV records (with extras), the yaw plot and the annotated video."""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from roadgaze.errors import RoadgazeError
from roadgaze.outputs import (
    AnnotatedVideoWriter,
    CsvWriter,
    JsonlWriter,
    YawPlot,
    annotate,
    sample_record,
)
from roadgaze.pipeline import ProcessedFrame, StageTimes
from roadgaze.types import Detection, FaceFeatures, Frame, YawSample

FACE = FaceFeatures(
    x_left_px=100.0,
    x_right_px=180.0,
    x_center_px=150.0,
    roll_deg=10.0,
    box_px=(95.0, 60.0, 185.0, 170.0),
    quality=0.9,
    landmarks_px=np.array([[100, 100, 0], [180, 110, 0], [150, 160, 0]], np.float32),
)
WITH_FACE = YawSample(0.5, 15, True, 20.25, 19.5, -3.0, 1.25, FACE, 1)
WITHOUT_FACE = YawSample(0.0, 0, False, None, None, None, None, None, 0)


def test_sample_record_fields_and_nulls() -> None:
    record = sample_record(WITH_FACE)
    assert record["t_s"] == 0.5 and record["frame"] == 15 and record["face"] is True
    assert (record["yaw_raw_deg"], record["yaw_deg"]) == (20.25, 19.5)
    assert (record["yaw_rate_dps"], record["yaw_std_deg"]) == (-3.0, 1.25)
    assert (record["x_left"], record["x_right"], record["x_center"]) == (100.0, 180.0, 150.0)
    empty = sample_record(WITHOUT_FACE)
    assert empty["face"] is False
    for key in ("yaw_raw_deg", "yaw_deg", "yaw_rate_dps", "yaw_std_deg", "x_left", "x_center"):
        assert empty[key] is None


def test_jsonl_one_object_per_line_with_extras(tmp_path: Path) -> None:
    path = tmp_path / "sub" / "frames.jsonl"
    with JsonlWriter(path, extras=[lambda s: {"on_road": s.face, "state": "ok"}]) as writer:
        writer.on_sample(WITHOUT_FACE)
        writer.on_sample(WITH_FACE)
    lines = path.read_text().splitlines()
    assert len(lines) == 2
    first, second = (json.loads(line) for line in lines)
    assert first["yaw_deg"] is None and first["on_road"] is False
    assert second["yaw_deg"] == 19.5 and second["state"] == "ok"


def test_jsonl_to_a_stream_is_not_closed() -> None:
    stream = io.StringIO()
    writer = JsonlWriter(stream)
    writer.on_sample(WITH_FACE)
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
        writer.on_sample(WITHOUT_FACE)
        writer.on_sample(WITH_FACE)
    rows = list(csv.DictReader(path.open()))
    assert len(rows) == 2
    assert rows[0]["yaw_deg"] == "" and rows[1]["yaw_deg"] == "19.5"
    assert rows[1]["x_center"] == "150.0"


def test_plot_is_a_png(tmp_path: Path) -> None:
    path = tmp_path / "yaw.png"
    with YawPlot(path) as plot:
        for i in range(20):
            plot.on_sample(YawSample(i / 10, i, True, float(i), float(i) - 0.5, 1.0, 1.0, FACE))
        plot.on_sample(WITHOUT_FACE)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert cv2.imread(str(path)) is not None


def test_annotate_draws_lines_gauge_and_text_without_touching_the_input() -> None:
    image = np.zeros((240, 320, 3), np.uint8)
    drawn = annotate(image, WITH_FACE, "LOOKING AWAY")
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
    with AnnotatedVideoWriter(path, fps=10.0, state_text=lambda s: "state") as writer:
        for i in range(8):
            sample = WITH_FACE if i % 2 else WITHOUT_FACE
            frame = Frame(i, i / 10, np.full((240, 320, 3), 40, np.uint8))
            times = StageTimes(0, 0, 0, 0, 0, 0)
            writer.on_frame(ProcessedFrame(frame, Detection((), None), sample, times))
    capture = cv2.VideoCapture(str(path))
    assert capture.get(cv2.CAP_PROP_FRAME_COUNT) == 8
    assert (capture.get(cv2.CAP_PROP_FRAME_WIDTH), capture.get(cv2.CAP_PROP_FRAME_HEIGHT)) == (
        320,
        240,
    )
    capture.release()
