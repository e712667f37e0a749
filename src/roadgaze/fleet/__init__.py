"""Fleet replay: many recorded drives through the pipeline, as resumable Parquet with a summary."""

from roadgaze.fleet.batch import BatchOptions, run_batch, write_summary
from roadgaze.fleet.drives import (
    MANIFEST_COLUMNS,
    VIDEO_SUFFIXES,
    Drive,
    derived_drive_ids,
    discover_drives,
    read_manifest,
)
from roadgaze.fleet.engines import LocalEngine, RayEngine
from roadgaze.fleet.executors import LocalExecutor, RayExecutor, available_cores
from roadgaze.fleet.recorder import DriveRecorder
from roadgaze.fleet.report import render_report
from roadgaze.fleet.results import ALERT_KINDS, DriveResult
from roadgaze.fleet.summary import BatchOutcome, GroupStats, by_driver, group_stats, summary_table
from roadgaze.fleet.tables import alerts_schema, frames_schema
from roadgaze.fleet.task import DriveTask, find_done, output_paths, process_drive

__all__ = [
    "ALERT_KINDS",
    "MANIFEST_COLUMNS",
    "VIDEO_SUFFIXES",
    "BatchOptions",
    "BatchOutcome",
    "Drive",
    "DriveRecorder",
    "DriveResult",
    "DriveTask",
    "GroupStats",
    "LocalEngine",
    "LocalExecutor",
    "RayEngine",
    "RayExecutor",
    "alerts_schema",
    "available_cores",
    "by_driver",
    "derived_drive_ids",
    "discover_drives",
    "find_done",
    "frames_schema",
    "group_stats",
    "output_paths",
    "process_drive",
    "read_manifest",
    "render_report",
    "run_batch",
    "summary_table",
    "write_summary",
]
