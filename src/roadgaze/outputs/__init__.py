"""Outputs: the flat per-frame record and its writers (JSONL, CSV), the plot and annotated video."""

from roadgaze.outputs.annotate import (
    PANEL_LINES,
    AlertBoard,
    AnnotatedVideoWriter,
    Banner,
    annotate,
    verdict_text,
)
from roadgaze.outputs.offline import fill_offline_columns
from roadgaze.outputs.plots import SERIES, Series, YawPlot, label_rows
from roadgaze.outputs.progress import ProgressBar
from roadgaze.outputs.records import (
    ALERT_SCHEMA,
    OFFLINE_FIELDS,
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
    "OFFLINE_FIELDS",
    "PANEL_LINES",
    "RECORD_FIELDS",
    "RECORD_SCHEMA",
    "SERIES",
    "AlertBoard",
    "AnnotatedVideoWriter",
    "Banner",
    "CsvWriter",
    "FieldType",
    "JsonlWriter",
    "ProgressBar",
    "Series",
    "YawPlot",
    "alert_fields",
    "annotate",
    "fill_offline_columns",
    "label_rows",
    "open_for_writing",
    "open_video_writer",
    "record_fields",
    "rounded",
    "verdict_text",
]
