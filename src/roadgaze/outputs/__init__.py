"""Outputs: the flat per-frame record and its writers (JSONL, CSV), the plot and annotated video."""

from roadgaze.outputs.annotate import AnnotatedVideoWriter, annotate, verdict_text
from roadgaze.outputs.plots import YawPlot
from roadgaze.outputs.progress import ProgressBar
from roadgaze.outputs.records import (
    ALERT_SCHEMA,
    RECORD_FIELDS,
    RECORD_SCHEMA,
    CsvWriter,
    FieldType,
    JsonlWriter,
    alert_fields,
    open_for_writing,
    record_fields,
    rounded,
)
from roadgaze.outputs.video import FOURCC_BY_SUFFIX, open_video_writer

__all__ = [
    "ALERT_SCHEMA",
    "FOURCC_BY_SUFFIX",
    "RECORD_FIELDS",
    "RECORD_SCHEMA",
    "AnnotatedVideoWriter",
    "CsvWriter",
    "FieldType",
    "JsonlWriter",
    "ProgressBar",
    "YawPlot",
    "alert_fields",
    "annotate",
    "open_for_writing",
    "open_video_writer",
    "record_fields",
    "rounded",
    "verdict_text",
]
