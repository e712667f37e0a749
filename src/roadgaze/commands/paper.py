"""`roadgaze paper-tables`: the paper's Tables III and IV (and Figs. 4/5 with --plots)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from roadgaze.config import Config
from roadgaze.logs import log_written


def register(subparsers: Any) -> None:
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "paper-tables",
        help="print RMSE and max error of the five yaw models on the paper's synthetic experiments",
        description="Reproduce Tables III and IV of Narayanan et al. (2014): RMSE and maximum "
        "error per yaw model for |true yaw| in [0,30], [30,60], [60,90] and [0,90] deg.",
    )
    parser.add_argument("--plots", type=Path, metavar="DIR", help="write Fig. 4/5-style PNGs here")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace, config: Config) -> int:
    from roadgaze.evaluation.paper import (
        experiment_1,
        experiment_2,
        format_table,
        range_errors,
        save_plots,
    )

    for stem, experiment in (("experiment1", experiment_1()), ("experiment2", experiment_2())):
        print(format_table(experiment, range_errors(experiment)))
        print()
        if args.plots is not None:
            for path in save_plots(experiment, args.plots, stem):
                log_written(path)
    return 0
