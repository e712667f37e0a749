"""The `roadgaze` command: a thin argparse layer over the typed functions of each stage.

Each sub-command lives in a module of `roadgaze.commands`, found automatically, that registers
itself with `register(subparsers)` (and may set `ORDER`, an int, for its place in `--help`);
heavy imports (MediaPipe, Zenoh, OpenCV) happen inside the handlers so `roadgaze --help` is fast.
A `RoadgazeError` ends in one line on stderr and its exit code, never a traceback.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import pkgutil
import sys
from collections.abc import Sequence
from types import ModuleType

from roadgaze import __version__, commands
from roadgaze.errors import RoadgazeError
from roadgaze.logs import setup_logging


def _command_modules() -> list[ModuleType]:
    """Every module in roadgaze.commands, ordered by its ORDER (then name) for `--help`."""
    modules = [
        importlib.import_module(f"{commands.__name__}.{info.name}")
        for info in pkgutil.iter_modules(commands.__path__)
    ]
    return sorted(modules, key=lambda module: (getattr(module, "ORDER", 100), module.__name__))


log = logging.getLogger("roadgaze")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="roadgaze",
        description="Driver head-yaw monitoring for forward-collision warning.",
    )
    parser.add_argument("--version", action="version", version=f"roadgaze {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for module in _command_modules():
        module.register(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the process exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    setup_logging(getattr(args, "log_level", None), getattr(args, "log_json", False))
    try:
        code: int = args.handler(args)
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
    return code
