"""One module per `roadgaze` sub-command; each exposes `register(subparsers)`.

`common_options()` is the parent parser every command that reads configuration shares, and
`config_from_args()` turns those options into a `Config`.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from roadgaze.config import Config, load_config, parse_overrides


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
    """The configuration named by the common options (file, environment, --set)."""
    return load_config(args.config, parse_overrides(args.set))
