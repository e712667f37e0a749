"""`roadgaze conformance [--protocol P] [--out DIR] [--fast] [--dossier FILE [--score]]`: the
protocols' requirements, checked.

Renders the scenario matrix (`roadgaze.conformance.matrix`) with the synthetic renderer, runs the
service on every clip at its speed and prints, for every requirement, its source, the expected
window, the measured warning time and PASS/FAIL; writes DIR/conformance.md and
DIR/conformance.json (and keeps the clips, their truth and speed tracks in DIR/clips). With
`--dossier FILE` it fills Euro NCAP's driver-monitoring prediction sheet from the run (and
DIR/dossier.md); `--score` scores it with Euro NCAP's rating calculator (docs/euroncap.md). Exit
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
    parser.add_argument(
        "--dossier",
        type=Path,
        metavar="FILE.xlsx",
        help="fill Euro NCAP's driver-monitoring prediction sheet (the template of the rating "
        "calculator, roadgaze[euroncap]) from the run: GREEN only where measured passing",
    )
    parser.add_argument(
        "--score",
        action="store_true",
        help="score the dossier with Euro NCAP's rating calculator (its verification tests "
        "answered by the service) and print 'Driver Monitoring: X / 25 points'",
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
    template = _template(args, config, out_dir)
    eyes = EyeRenderer(load_photo(), SIZE, config=config, eyeball_at_rest=True)
    renderer = ScenarioRenderer(eyes, FPS, config.monitor.cabin)

    def progress(scenario: Any, outcomes: list[Any]) -> None:
        verdict = "FAIL" if any(o.result == "FAIL" for o in outcomes) else "PASS"
        measured = ", ".join(
            f"{o.requirement.key.rpartition('.')[2]} "
            + ("none" if o.measured_s is None else f"{o.measured_s:.2f} s")
            for o in outcomes
        )
        log.info("conformance: %s %s (%s)", verdict, scenario.name, measured)

    suite = run_suite(scenarios, config, out_dir / "clips", renderer, progress, args.save_clips)
    print(markdown_table(suite.outcomes), flush=True)
    log.info("conformance: %s", summary_line(suite, protocol))
    for path in write_reports(suite, protocol, FPS, out_dir):
        log_written(path)
    if template is not None:
        _dossier(args, config, suite.outcomes, renderer, template, out_dir)
    return EXIT_FAILED if suite.failed else 0


def _template(args: argparse.Namespace, config: Config, out_dir: Path) -> Path | None:
    """With --dossier: the checked template of the installed calculator (before any drive)."""
    if args.dossier is None:
        if args.score:
            raise ConfigError("--score scores the dossier: pass --dossier FILE.xlsx too")
        return None
    from roadgaze.conformance.dossier_score import Calculator, require_calculator
    from roadgaze.conformance.dossier_xlsx import check_template

    dossier: Path = args.dossier
    if dossier.suffix.lower() != ".xlsx" or dossier.is_dir():
        raise ConfigError(f"--dossier {dossier}: expected a FILE.xlsx (the calculator's format)")
    if not dossier.parent.resolve().is_dir():
        raise ConfigError(f"--dossier {dossier}: the folder {dossier.parent} does not exist")
    if config.monitor.protocol == "addw":
        raise ConfigError("--dossier needs Euro NCAP's rules: pass --protocol euroncap (or both)")
    require_calculator()
    import openpyxl  # installed with the calculator

    template = Calculator(out_dir / "euroncap").template()
    wb = openpyxl.load_workbook(template)
    try:
        check_template(wb)
    finally:
        wb.close()
    return template


def _dossier(
    args: argparse.Namespace,
    config: Config,
    outcomes: tuple[Any, ...],
    renderer: Any,
    template: Path,
    out_dir: Path,
) -> None:
    """Judge the dossier from the run, write it (and DIR/dossier.md), score it with --score."""
    from roadgaze.conformance.dossier import judge, with_gates_met
    from roadgaze.conformance.dossier_report import dossier_markdown, score_lines
    from roadgaze.conformance.dossier_score import Calculator, score
    from roadgaze.conformance.dossier_xlsx import write_dossier
    from roadgaze.conformance.matrix import scenario_matrix
    from roadgaze.conformance.run import run_suite

    runs: dict[str, list[Any]] = {}

    def runner(batch: Any) -> list[Any]:
        for scenario in batch:
            if scenario.name not in runs:
                log.info("conformance: running %s again for the dossier", scenario.name)
                suite = run_suite([scenario], config, out_dir / "clips", renderer)
                runs[scenario.name] = list(suite.outcomes)
        return [outcome for scenario in batch for outcome in runs[scenario.name]]

    scenarios = scenario_matrix(config.monitor)
    dossier = judge(outcomes, scenarios, runner, config.monitor.cabin, config.monitor.min_speed_kmh)
    log_written(write_dossier(template, dossier, args.dossier))
    markdown = dossier_markdown(dossier)
    print(f"\n{markdown}", flush=True)
    (out_dir / "dossier.md").write_text(markdown, encoding="utf-8")
    log_written(out_dir / "dossier.md")
    if not args.score:
        return
    work = out_dir / "euroncap"
    official = score(dossier, args.dossier, Calculator(work), scenarios, runner)
    log_written(official.report)
    alone = None
    if dossier.gates():
        opened = with_gates_met(dossier)
        copy = write_dossier(template, opened, work / "rows-alone.xlsx")
        alone = score(opened, copy, Calculator(work / "rows-alone"), scenarios, runner, True).score
    print("\n".join(score_lines(official, dossier, alone)), flush=True)
