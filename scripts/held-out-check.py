"""The issue-21 acceptance check on every Pointing'04 development subject (real faces).

Usage: PYTHONPATH=src python scripts/held-out-check.py [DATASET] [--subjects 1,2] [--series 1,2]
       [--cases NAME,...] [--jobs N] [--set SECTION.FIELD=VALUE ...]

Builds, for each subject, series and case of `roadgaze.evaluation.held_out.CASES`, a 15 fps clip
(frontal still, the look's still held, frontal again), runs it through the pipeline at the case's
speed and prints one line per failure, then the pass rate per case with the warning times
(seconds after the look's start: median, min, max). Exits 1 when any case failed.
"""

from __future__ import annotations

import argparse
import statistics
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from roadgaze.config import Config, load_config
from roadgaze.evaluation.held_out import CASES, Case, CaseResult, Stills, load_stills, run_case
from roadgaze.evaluation.pointing04 import default_dataset
from roadgaze.logs import setup_logging

# $ROADGAZE_DATA/pointing04-dev, else the evaluation data beside the checkout (as tests find it).
DEFAULT_DATA = default_dataset() or (
    Path(__file__).resolve().parents[1].parent / "shared" / "data" / "pointing04-dev"
)


def _run(job: tuple[Stills, Case, Config]) -> CaseResult:
    setup_logging()
    return run_case(*job)


def _numbers(text: str | None) -> set[int] | None:
    return None if text is None else {int(part) for part in text.split(",") if part}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dataset", nargs="?", type=Path, default=DEFAULT_DATA)
    parser.add_argument("--subjects", help="comma-separated subject numbers (default: all)")
    parser.add_argument("--series", default="1", help="comma-separated series (default: 1)")
    parser.add_argument("--cases", help="comma-separated case names (default: all)")
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="SECTION.FIELD=VALUE",
        help="override one configuration value, e.g. monitor.protocol=addw",
    )
    args = parser.parse_args()
    subjects, series = _numbers(args.subjects), _numbers(args.series)
    cases = [c for c in CASES if args.cases is None or c.name in args.cases.split(",")]
    all_stills = [
        s
        for s in load_stills(args.dataset)
        if (subjects is None or s.subject in subjects) and (series is None or s.series in series)
    ]
    config = load_config(overrides=dict(item.split("=", 1) for item in args.set))
    jobs = [(stills, case, config) for stills in all_stills for case in cases]
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        results = list(pool.map(_run, jobs))
    for r in results:
        if r.support_failed:
            where = f"subject {r.subject} series {r.series} {r.case.name}"
            print(f"SUPPORT {where}: {r.support_failed}")
        if not r.passed:
            zones = sorted({z for z in r.look_zones}, key=str)
            yaw = "-" if r.look_yaw_deg is None else f"{r.look_yaw_deg:.1f}"
            alerts = ", ".join(f"{kind}@{t:.2f}" for t, kind, _ in r.alerts)
            print(
                f"FAIL subject {r.subject} series {r.series} {r.case.name}: {r.why_failed}; "
                f"yaw {yaw}, zones {zones}; alerts [{alerts}]"
            )
    print(
        f"\n{'case':24} {'pass':>7}  warning s after the look's start (median, min-max); "
        "forward support raised within 0.5 s"
    )
    failed = 0
    for case in cases:
        mine = [r for r in results if r.case == case]
        passed = sum(r.passed for r in mine)
        failed += len(mine) - passed
        times = [r.warn_s for r in mine if r.warn_s is not None]
        span = (
            f"{statistics.median(times):.2f} ({min(times):.2f}-{max(times):.2f}) n={len(times)}"
            if times
            else "-"
        )
        supported = sum(not r.support_failed for r in mine)
        print(f"{case.name:24} {passed:>3}/{len(mine):<3}  {span}; support {supported}/{len(mine)}")
    total = len(results)
    print(f"{'all':24} {total - failed:>3}/{total:<3}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
