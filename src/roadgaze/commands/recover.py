"""`roadgaze recover FILE`: an MCAP recording cut short (kill -9, power loss) made whole."""

from __future__ import annotations

import argparse
import logging
from pathlib import Path
from typing import Any

from roadgaze.commands.options import check_output_paths, common_options
from roadgaze.config import Config
from roadgaze.logs import log_written

log = logging.getLogger("roadgaze.recover")


def register(subparsers: Any) -> None:
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "recover",
        parents=[common_options()],
        help="make an MCAP recording cut short (kill -9, power loss) whole and indexed",
        description="Read an MCAP recording in order up to its last complete chunk and write "
        "every message read into a new, indexed file (NAME.mcap.part -> NAME.mcap, else "
        "NAME.recovered.mcap). An existing file is never overwritten: when that name is taken "
        "the first free NAME-1.mcap, NAME-2.mcap, ... is written (and said); an --out that "
        "exists is refused (exit 2). Lost: the chunk being written when the recording stopped (at "
        "most record.flush_s of data). `run --record` does this itself for the segments a "
        "killed run left in its folder. Needs roadgaze[foxglove].",
    )
    parser.add_argument("source", type=Path, metavar="FILE", help="the MCAP file to recover")
    parser.add_argument("--out", type=Path, metavar="FILE", help="where to write the whole file")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace, config: Config) -> int:
    from roadgaze.errors import SourceError
    from roadgaze.outputs.foxglove import require_foxglove

    require_foxglove("roadgaze recover")
    from roadgaze.outputs.foxglove.recover import recover_mcap, recovered_name

    if not args.source.is_file():
        raise SourceError(f"MCAP file {args.source} not found")
    out = args.out if args.out is not None else recovered_name(args.source)
    check_output_paths({"FILE": args.source}, {"--out": out}, {"--out": (".mcap",)})
    recovery = recover_mcap(
        args.source, out, exact=args.out is not None, max_chunk_mib=config.record.max_chunk_mib
    )
    log.info("recover %s: %s", args.source, recovery.describe())
    if recovery.path != out:
        log.warning("%s exists (another file, never overwritten): wrote %s", out, recovery.path)
    log_written(recovery.path)
    return 0
