"""`roadgaze data pointing04 SRC OUT`: an evaluation set from the public Pointing'04 archive."""

from __future__ import annotations

import argparse
import logging
from typing import Any

from roadgaze.commands.options import common_options
from roadgaze.config import Config


def register(subparsers: Any) -> None:
    from pathlib import Path

    parser: argparse.ArgumentParser = subparsers.add_parser(
        "data",
        help="build an evaluation set (images and ground_truth.csv) from a public archive",
        description="Build the evaluation set that `roadgaze eval` reads from a public data "
        "set's archive, as unpacked.",
    )
    sets = parser.add_subparsers(dest="dataset", metavar="DATASET", required=True)
    pointing04 = sets.add_parser(
        "pointing04",
        parents=[common_options()],
        help="Pointing'04 (Head Pose Image Database): images and ground_truth.csv",
        description="Find every image named personne<PP><S><II><tilt><pan>.jpg under SRC (the "
        "unpacked Head Pose Image Database of Gourier, Hall and Crowley 2004), copy it to "
        "OUT/images/PersonPP/ (OUT outside SRC; symbolic links under SRC are skipped, never "
        "followed) and write OUT/ground_truth.csv with the columns file, yaw_deg, "
        "pitch_deg, pan_label, tilt_label, subject, series. yaw_deg = -pan (the archive's pan "
        "is positive turned to the subject's own right, roadgaze's yaw to their own left); "
        "pitch_deg = tilt. Then: roadgaze eval OUT. With OUT = $ROADGAZE_DATA/pointing04-dev, "
        "`roadgaze eval` and the tests find it without a folder.",
    )
    pointing04.add_argument("source", type=Path, metavar="SRC")
    pointing04.add_argument("out", type=Path, metavar="OUT")
    pointing04.add_argument(
        "--subjects",
        metavar="LIST",
        help="only these subjects (1-15), e.g. 1-10 (the development half the README's "
        "figures use)",
    )
    pointing04.add_argument(
        "--symlink", action="store_true", help="link the images instead of copying them"
    )
    pointing04.set_defaults(handler=run_pointing04)


def run_pointing04(args: argparse.Namespace, config: Config) -> int:
    from roadgaze.evaluation.pointing04 import (
        build_evaluation_set,
        check_folders,
        find_images,
        parse_subjects,
    )
    from roadgaze.logs import log_written

    subjects = None if args.subjects is None else parse_subjects(args.subjects)
    check_folders(args.source, args.out)
    images = find_images(args.source, subjects)
    csv_path = build_evaluation_set(images, args.out, symlink=args.symlink)
    logging.getLogger(__name__).info(
        "%d images of subjects %s in %s (yaw_deg = -pan)",
        len(images),
        ",".join(map(str, sorted({image.subject for image in images}))),
        args.out,
    )
    log_written(csv_path)
    return 0
