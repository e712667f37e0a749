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
    OFFLINE_FIELDS,
    RECORD_FIELDS,
    CsvWriter,
    JsonlWriter,
    open_for_writing,
    record_fields,
    rounded,
)
from roadgaze.outputs.video import FOURCC_BY_SUFFIX, open_video_writer

__all__ = [
    "FOURCC_BY_SUFFIX",
    "OFFLINE_FIELDS",
    "PANEL_LINES",
    "RECORD_FIELDS",
    "SERIES",
    "AlertBoard",
    "AnnotatedVideoWriter",
    "Banner",
    "CsvWriter",
    "JsonlWriter",
    "ProgressBar",
    "Series",
    "YawPlot",
    "annotate",
    "fill_offline_columns",
    "label_rows",
    "open_for_writing",
    "open_video_writer",
    "record_fields",
    "rounded",
    "verdict_text",
]
