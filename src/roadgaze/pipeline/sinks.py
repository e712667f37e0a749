"""The sinks a run's options ask for (writers, recorders), and the check that none of them
writes onto a file the run reads (`build_run`'s steps 2, 4 and 7)."""

from __future__ import annotations

import sys
from contextlib import ExitStack
from pathlib import Path
from typing import TYPE_CHECKING

from roadgaze.capture import FrameSource
from roadgaze.config import Config
from roadgaze.pipeline.bus import BusOutputs
from roadgaze.speed import SpeedChoice
from roadgaze.types import Sink

if TYPE_CHECKING:
    from roadgaze.pipeline.build import RunOptions


def check_paths(config: Config, options: RunOptions, choice: SpeedChoice) -> None:
    """Refuse (one `ConfigError`, before anything is written) an output onto a file the run
    reads, an input named as one of the `--record` folder's segments (pruned or recovered
    there), two outputs on one file, or a file type its writer cannot write
    (`roadgaze.outputs.paths`)."""
    from roadgaze.outputs.paths import PLOT_SUFFIXES, check_output_paths
    from roadgaze.outputs.video import FOURCC_BY_SUFFIX

    source = Path(options.source).expanduser()
    track_name = "--speed-track" if options.speed_track else f"the speed track beside {source}"
    inputs: dict[str, Path | None] = {
        "the source": source if source.exists() else None,
        track_name: choice.track_path,
        **options.inputs,
        "model.path": config.model.path,
        "zenoh.config_file": config.zenoh.config_file,
    }
    check_output_paths(
        inputs,
        {
            "--out": options.records if options.records != "-" else None,
            "--csv": options.csv,
            "--plot": options.plot,
            "--annotate": options.annotate,
            "--mcap": options.mcap,
        },
        {"--plot": PLOT_SUFFIXES, "--annotate": tuple(FOURCC_BY_SUFFIX), "--mcap": (".mcap",)},
        {"--record": (options.record_dir, segment_pattern(config, options))},
    )


def segment_pattern(config: Config, options: RunOptions) -> str:
    """The names of the segments `--record` writes, rotates, prunes and recovers."""
    if options.record_dir is None:
        return ""
    from roadgaze.outputs.foxglove.open import segment_prefix  # needs roadgaze[foxglove]

    return f"{segment_prefix(config)}-*.mcap*"


def recorders(
    config: Config,
    options: RunOptions,
    bus: BusOutputs,
    source: FrameSource | None,
    stack: ExitStack,
) -> list[Sink]:
    """The replay's MCAP file, or the vehicle's segments and live view, as the options ask."""
    found: list[Sink] = []
    if options.mcap is not None:
        from roadgaze.outputs.foxglove.open import replay_recorder

        flat_out = not options.realtime and source is not None and not source.info.live
        recorder = replay_recorder(
            config, options.source, options.mcap, bus.health.state_json, block_on_images=flat_out
        )
        found.append(stack.enter_context(recorder))
    if options.record_dir is not None or options.foxglove is not None:
        from roadgaze.outputs.foxglove.open import vehicle_recorder

        vehicle = vehicle_recorder(
            config, options.source, options.record_dir, options.foxglove, bus.health.state_json
        )
        bus.health.problem_checks.append(vehicle.problem)
        found.append(stack.enter_context(vehicle))
    return found


def writers(
    config: Config, options: RunOptions, source: FrameSource, stack: ExitStack
) -> list[Sink]:
    """The writer sinks the options ask for, each closed at the end of the run."""
    from roadgaze.outputs import AnnotatedVideoWriter, CsvWriter, JsonlWriter, ProgressBar, YawPlot

    info = source.info
    writers: list[Sink] = []
    if options.records is not None:
        target = sys.stdout if options.records == "-" else Path(options.records)
        writers.append(stack.enter_context(JsonlWriter(target)))
    if options.csv is not None:
        writers.append(stack.enter_context(CsvWriter(options.csv)))
    if options.plot is not None:
        title = Path(info.name).name
        writers.append(stack.enter_context(YawPlot(options.plot, title, monitor=config.monitor)))
    if options.annotate is not None:
        video = AnnotatedVideoWriter(options.annotate, info.fps or 30.0, monitor=config.monitor)
        writers.append(stack.enter_context(video))
    if options.progress is not None:
        total = info.frame_count
        if options.max_frames is not None and total is not None:
            total = min(total, options.max_frames)
        writers.append(stack.enter_context(ProgressBar(total, description=options.progress)))
    return writers
