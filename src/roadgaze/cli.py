"""The `roadgaze` command: a thin argparse layer over the typed functions of each stage.

The commands are listed in `roadgaze.commands.COMMANDS`. Every command gets its configuration
(defaults < `--config` < environment < `--set`) and logging set from it (`--log-level` and
`--log-json` win). A `RoadgazeError` ends in one line on stderr and its exit code, never a
traceback.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from roadgaze import __version__
from roadgaze.commands import COMMANDS
from roadgaze.commands.options import config_from_args
from roadgaze.errors import RoadgazeError
from roadgaze.logs import setup_logging


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="roadgaze",
        description="Driver head-yaw monitoring for forward-collision warning.",
    )
    parser.add_argument("--version", action="version", version=f"roadgaze {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for module in COMMANDS:
        module.register(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the process exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    log_level = getattr(args, "log_level", None)
    log_json = bool(getattr(args, "log_json", False))
    setup_logging(log_level, log_json)
    try:
        config = config_from_args(args)
        setup_logging(log_level or config.logging.level, log_json or config.logging.json_format)
        code: int = args.handler(args, config)
    except RoadgazeError as exc:
        print(f"roadgaze {args.command}: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print(f"roadgaze {args.command}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # The reader of our stdout went away (e.g. `| head`): not an error of ours.
        sys.stderr.close()
        return 0
    except OSError as exc:
        # A full disk or a vanished folder while writing: outputs closed so far are kept.
        where = f": {exc.filename}" if exc.filename else ""
        print(f"roadgaze {args.command}: error: {exc.strerror or exc}{where}", file=sys.stderr)
        return 2
    return code
