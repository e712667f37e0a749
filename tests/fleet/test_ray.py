"""The Ray engine: the same task function as Ray tasks on a real local Ray instance writes the
same Parquet as the local engine."""

from __future__ import annotations

import logging
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pyarrow.parquet as pq
import pytest

from roadgaze.config import Config
from roadgaze.fleet import BatchOptions, discover_drives, output_paths, run_batch

ray = pytest.importorskip("ray", reason="Ray is the optional extra roadgaze[ray]")

pytestmark = pytest.mark.slow

TIMING = {"processing_fps", "startup_s", "wall_s"}


@pytest.fixture(scope="session")
def ray_instance() -> Iterator[Any]:
    """One local Ray instance with one CPU for the whole session (about 3 s to start)."""
    ray.init(num_cpus=1, include_dashboard=False, log_to_driver=False, logging_level=logging.ERROR)
    yield ray
    ray.shutdown()


def test_ray_tasks_write_the_same_parquet_as_the_local_engine(
    ray_instance: Any, local_batch: Any, tmp_path: Path
) -> None:
    out = tmp_path / "ray-out"
    options = BatchOptions(out_dir=out, engine="ray", progress=False)
    outcome = run_batch(discover_drives(local_batch.input.folder), Config(), options)
    assert ray_instance.is_initialized()  # a Ray started by the caller is left running
    assert outcome.engine == "ray" and outcome.workers == 1
    for drive_id in local_batch.input.videos:
        for ray_path, local_path in zip(
            output_paths(out, drive_id), output_paths(local_batch.out_dir, drive_id), strict=True
        ):
            ray_table, local_table = pq.read_table(ray_path), pq.read_table(local_path)
            assert ray_table.num_rows > 0 or "alerts" in str(ray_path)
            assert ray_table.equals(local_table), drive_id
    ray_rows = pq.read_table(out / "summary.parquet").to_pylist()
    local_rows = pq.read_table(local_batch.out_dir / "summary.parquet").to_pylist()
    assert [{k: v for k, v in row.items() if k not in TIMING} for row in ray_rows] == [
        {k: v for k, v in row.items() if k not in TIMING} for row in local_rows
    ]
    assert {r["drive_id"]: r["status"] for r in ray_rows}["corrupt"] == "failed"
