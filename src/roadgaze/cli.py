"""The `roadgaze` command: a thin argparse layer over the typed functions of each stage.

The commands are listed in `roadgaze.commands.COMMANDS`. Every command gets its configuration
(defaults < `--config` < environment < `--set`) and logging set from it (`--log-level` and
`--log-json` win). A `RoadgazeError` ends in one line on stderr and its exit code, never a
traceback.
"""

from __future__ import annotations

import argparse
import difflib
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
        description=(
            "Real-time driver monitoring for forward-collision warning: where the driver looks, "
            "eye closure and drowsiness, by the EU ADDW and Euro NCAP rules, told over Zenoh."
        ),
    )
    parser.add_argument("--version", action="version", version=f"roadgaze {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for module in COMMANDS:
        module.register(subparsers)
    return parser


def unknown_command(parser: argparse.ArgumentParser, argv: Sequence[str]) -> str | None:
    """The one-line error for a mistyped command, with the nearest command names; None when the
    command is known (or absent: argparse says what is missing)."""
    names = [
        name
        for action in parser._actions
        if isinstance(action, argparse._SubParsersAction)
        for name in action.choices
    ]
    first = next((word for word in argv if not word.startswith("-")), None)
    if first is None or first in names:
        return None
    near = [name for name in names if name.startswith(first)][:2] or difflib.get_close_matches(
        first, names, n=2, cutoff=0.6
    )
    hint = f"did you mean {' or '.join(near)}? " if near else ""
    return f"roadgaze: error: unknown command '{first}'; {hint}roadgaze --help lists them"


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the process exit code."""
    words = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser()
    mistyped = unknown_command(parser, words)
    if mistyped is not None:
        print(mistyped, file=sys.stderr)
        return 2
    args = parser.parse_args(words)
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
