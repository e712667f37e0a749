"""Command-line flags shared by several commands: configuration, logging and Zenoh."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from roadgaze.config import Config, ZenohConfig, load_config, parse_overrides
from roadgaze.errors import ConfigError
from roadgaze.outputs.paths import PLOT_SUFFIXES, check_output_paths

__all__ = [
    "PLOT_SUFFIXES",
    "add_speed_options",
    "add_zenoh_options",
    "check_output_paths",
    "check_seconds",
    "common_options",
    "config_from_args",
    "with_zenoh_args",
    "zenoh_config_from_args",
]


def common_options() -> argparse.ArgumentParser:
    """--config, --set, --log-level and --log-json, for use as `parents=[common_options()]`."""
    parent = argparse.ArgumentParser(add_help=False)
    group = parent.add_argument_group("configuration")
    group.add_argument("--config", type=Path, metavar="FILE", help="TOML configuration file")
    group.add_argument(
        "--set",
        action="append",
        metavar="SECTION.FIELD=VALUE",
        help="override one configuration value (repeatable), e.g. --set monitor.min_speed_kmh=30",
    )
    group.add_argument(
        "--log-level", choices=["DEBUG", "INFO", "WARNING", "ERROR"], help="log level"
    )
    group.add_argument("--log-json", action="store_true", help="log one JSON object per line")
    return parent


def config_from_args(args: argparse.Namespace) -> Config:
    """The configuration named by the common options (file, environment, --set); the defaults
    (and the environment) for a command without them."""
    return load_config(getattr(args, "config", None), parse_overrides(getattr(args, "set", None)))


def add_zenoh_options(parser: Any) -> None:
    """Command-line options shared by run, replay --publish and listen."""
    group = parser.add_argument_group("zenoh")
    group.add_argument(
        "--vehicle-id", metavar="ID", help="vehicle id in the key expressions ([A-Za-z0-9_-]{1,64})"
    )
    group.add_argument(
        "--zenoh-config",
        type=Path,
        metavar="FILE",
        help="a Zenoh JSON5 configuration file (e.g. from `roadgaze security init`) as the base; "
        "the --zenoh-* options still override it",
    )
    group.add_argument(
        "--zenoh-connect",
        action="append",
        metavar="ENDPOINT",
        help="endpoint to connect to, e.g. tcp/127.0.0.1:7447 (repeatable)",
    )
    group.add_argument(
        "--zenoh-listen",
        action="append",
        metavar="ENDPOINT",
        help="endpoint to listen on (repeatable; peer mode)",
    )
    group.add_argument("--zenoh-mode", choices=["peer", "client"], help="zenoh session mode")
    group.add_argument(
        "--vss",
        action="store_true",
        help="also publish (run, replay --publish) or show (listen) the COVESA VSS driver "
        "signals, e.g. Vehicle/Driver/IsEyesOnRoad (zenoh.vss)",
    )


def zenoh_config_from_args(config: ZenohConfig, args: Any) -> ZenohConfig:
    """`config` with the --vehicle-id/--zenoh-* options applied (validated again).

    `--vehicle-id` must be a real id here (a daemon publishes under it); `listen` handles `*`.
    """
    update: dict[str, Any] = {}
    if getattr(args, "vehicle_id", None) is not None:
        update["vehicle_id"] = args.vehicle_id
    if getattr(args, "zenoh_config", None) is not None:
        update["config_file"] = args.zenoh_config
    if getattr(args, "zenoh_connect", None):
        update["connect"] = list(args.zenoh_connect)
    if getattr(args, "zenoh_listen", None):
        update["listen"] = list(args.zenoh_listen)
    if getattr(args, "zenoh_mode", None):
        update["mode"] = args.zenoh_mode
    if getattr(args, "vss", False):
        update["vss"] = True
    if not update:
        return config
    merged = {name: getattr(config, name) for name in config.model_fields_set} | update
    try:
        return ZenohConfig.model_validate(merged)
    except ValidationError as exc:
        problems = "; ".join(
            f"{'.'.join(map(str, e['loc']))}: {e['msg']}".replace("vehicle_id", "--vehicle-id")
            for e in exc.errors()
        )
        raise ConfigError(f"bad zenoh option: {problems}") from None


def with_zenoh_args(config: Config, args: Any) -> Config:
    """`config` with its `[zenoh]` section updated by the --vehicle-id/--zenoh-* options."""
    return config.model_copy(update={"zenoh": zenoh_config_from_args(config.zenoh, args)})


def add_speed_options(parser: Any, *, track: bool = True) -> None:
    """--speed-track and --speed-kmh: the vehicle speed of a recorded drive
    (`roadgaze.capture.speed_track`)."""
    group = parser.add_argument_group("vehicle speed of a recorded drive")
    if track:
        group.add_argument(
            "--speed-track",
            type=Path,
            metavar="FILE",
            help="CSV or Parquet with columns t_s,kmh on the video's timeline (default: "
            "VIDEO's <stem>.speed.csv or .speed.parquet beside it, when there is one); the last "
            "sample holds for zenoh.speed_timeout_s, before the first and in gaps the speed is "
            "unknown (taken as moving)",
        )
    group.add_argument(
        "--speed-kmh",
        type=float,
        metavar="N",
        help="one speed in km/h for the whole drive (instead of a track)",
    )


def check_seconds(option: str, value: float | None) -> None:
    """Raise ConfigError unless `value` (when given) is a finite number of seconds > 0: argparse
    takes 'nan' and 'inf' as floats, and a loop waiting for NaN seconds never ends."""
    if value is not None and not (math.isfinite(value) and value > 0):
        raise ConfigError(f"{option} must be a finite number of seconds > 0, found {value}")
