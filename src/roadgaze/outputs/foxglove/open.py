"""The recorders the commands open: a replay's MCAP file, the vehicle's segments and live view."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from roadgaze.config import Config
from roadgaze.outputs.foxglove.live import LiveServer, parse_address
from roadgaze.outputs.foxglove.recorder import FoxgloveRecorder
from roadgaze.outputs.foxglove.targets import McapFile, McapSegments, Target


def segment_prefix(config: Config) -> str:
    """The names of the vehicle's segments start with this (`roadgaze-car-0`)."""
    return f"roadgaze-{config.zenoh.vehicle_id}"


def replay_recorder(
    config: Config,
    source: str,
    path: Path,
    state: Callable[[], bytes] | None = None,
    block_on_images: bool = True,
) -> FoxgloveRecorder:
    """`replay --mcap FILE`: one file stamped on the video's timeline; a failed write ends the
    replay. Camera frames unless `record.images` is false."""
    images = config.record.images_for("replay")
    return FoxgloveRecorder(
        [McapFile(path, config.record, images)],
        config,
        images=images,
        source=source,
        state=state,
        strict=True,
        block_on_images=block_on_images,
    )


def vehicle_recorder(
    config: Config,
    source: str,
    folder: Path | None,
    live_address: str | None,
    state: Callable[[], bytes] | None = None,
) -> FoxgloveRecorder:
    """`run --record DIR` (segments; camera frames only if `record.images` is true) and/or
    `run --foxglove [HOST:]PORT` (the live view; camera frames unless `record.images` is false),
    stamped on the wall clock. A failed write is logged once and stops the recording, never the
    monitoring; camera frames are dropped (and counted) when the writer is behind."""
    targets: list[Target] = []
    settings = config.record
    if folder is not None:
        prefix = segment_prefix(config)
        targets.append(McapSegments(folder, settings, settings.images_for("vehicle"), prefix))
    if live_address is not None:
        host, port = parse_address(live_address)
        targets.append(LiveServer(host, port, settings.images_for("live")))
    images = (folder is not None and settings.images_for("vehicle")) or (
        live_address is not None and settings.images_for("live")
    )
    return FoxgloveRecorder(
        targets,
        config,
        images=images,
        source=source,
        wall_clock_stamps=True,
        state=state,
        strict=False,
        block_on_images=False,
    )
