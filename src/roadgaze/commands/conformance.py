"""`roadgaze conformance [--protocol P] [--out DIR] [--fast]`: the protocols' requirements, checked.

Renders the scenario matrix (`roadgaze.conformance.matrix`) with the synthetic renderer, runs the
service on every clip at its speed and prints, for every requirement, its source, the expected
window, the measured warning time and PASS/FAIL; writes DIR/conformance.md and
DIR/conformance.json (and keeps the clips, their truth and speed tracks in DIR/clips). Exit
status 1 when any requirement fails, 2 for bad arguments.
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path
from typing import Any

from roadgaze.commands.options import common_options
from roadgaze.config import Config
from roadgaze.errors import ConfigError
from roadgaze.logs import log_written

log = logging.getLogger("roadgaze.conformance")

EXIT_FAILED = 1
FPS = 15.0
SIZE = (320, 320)


def register(subparsers: Any) -> None:
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "conformance",
        parents=[common_options()],
        help="check the ADDW / Euro NCAP requirements on rendered drives with exact truth",
        description="Render every scenario (speed bands, glances by area, mirrors, glances just "
        "below each trigger, eyes-only glance, VATS, microsleep, sleep, unresponsive, a covered "
        "lens, frozen frames, no face, sunglasses, each camera preset), run the service on each "
        "at its speed (a speed track beside each clip) and print each requirement's source, "
        "expected window, measured warning time and PASS/FAIL. Exit 1 on any FAIL.",
    )
    parser.add_argument(
        "--protocol",
        choices=["addw", "euroncap", "both"],
        help="the protocol to check (default: the configuration's monitor.protocol)",
    )
    parser.add_argument(
        "--out",
        type=Path,
        default=Path("conformance"),
        metavar="DIR",
        help="where conformance.md, conformance.json and the clips go (default ./conformance)",
    )
    parser.add_argument(
        "--fast", action="store_true", help="only the fast subset (the test suite's, ~8 drives)"
    )
    parser.add_argument(
        "--save-clips",
        action="store_true",
        help="also write each drive's video (DIR/clips/NAME.mkv, lossless) for `roadgaze replay`",
    )
    parser.add_argument(
        "--only",
        action="append",
        metavar="NAME",
        help="only the scenario NAME (repeatable; names as in the table)",
    )
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace, config: Config) -> int:
    from roadgaze.conformance.clips import ScenarioRenderer
    from roadgaze.conformance.matrix import scenario_matrix
    from roadgaze.conformance.report import markdown_table, summary_line, write_reports
    from roadgaze.conformance.run import run_suite
    from roadgaze.synth import EyeRenderer, load_photo

    if args.protocol is not None:
        monitor = config.monitor.model_dump() | {"protocol": args.protocol}
        config = config.model_copy(update={"monitor": type(config.monitor).model_validate(monitor)})
    protocol = config.monitor.protocol
    scenarios = scenario_matrix(config.monitor)
    if args.fast:
        scenarios = [s for s in scenarios if s.fast]
    if args.only:
        known = {s.name for s in scenario_matrix(config.monitor)}
        unknown = sorted(set(args.only) - known)
        if unknown:
            raise ConfigError(
                f"unknown scenario {', '.join(unknown)}; scenarios: {', '.join(sorted(known))}"
            )
        scenarios = [s for s in scenarios if s.name in args.only]
    out_dir: Path = args.out
    if out_dir.is_file():
        raise ConfigError(f"--out {out_dir} is a file; pass a folder")
    eyes = EyeRenderer(load_photo(), SIZE, config=config, eyeball_at_rest=True)
    renderer = ScenarioRenderer(eyes, FPS, config.monitor.cabin)

    def progress(scenario: Any, outcomes: list[Any]) -> None:
        verdict = "PASS" if all(o.passed for o in outcomes) else "FAIL"
        measured = ", ".join(
            "none" if o.measured_s is None else f"{o.measured_s:.2f} s" for o in outcomes
        )
        log.info("conformance: %s %s (%s)", verdict, scenario.name, measured)

    suite = run_suite(scenarios, config, out_dir / "clips", renderer, progress, args.save_clips)
    print(markdown_table(suite.outcomes), flush=True)
    log.info("conformance: %s", summary_line(suite, protocol))
    for path in write_reports(suite, protocol, FPS, out_dir):
        log_written(path)
    return EXIT_FAILED if suite.failed else 0
