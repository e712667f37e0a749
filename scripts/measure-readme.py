#!/usr/bin/env python3
"""Regenerate the README's measured figures and print them as one Markdown block.

    .venv/bin/python scripts/measure-readme.py [--work DIR] [--repeat N] [--no-eval]
                                               [--soak SECONDS]
    .venv/bin/python scripts/measure-readme.py --check [--cheap] | --update

`--check` runs the command of every deterministic figure the README and docs state
(`scripts/documented_figures.py`: accuracy, synthetic recovery, smoothers, eyes, the paper's
tables) and exits 1, listing each difference, when a document no longer says what its command
prints; `--cheap` only the quick ones (what `tests/test_documented_figures.py` runs); `--update`
writes the printed values into the documents instead.

Without `--check`/`--update`, the timed figures (the Measured block):

Runs, with the `roadgaze` of the Python that runs this script:
1. `roadgaze demo --out WORK/demo`, timed (the demo's own render/service/total split too);
2. `roadgaze bench WORK/demo/drive.mp4 --json --repeat N --latency` on the demo's drive;
3. `roadgaze synth --measure` (the service yaw's recovery on synthetic stills with exact truth);
4. `roadgaze eval $ROADGAZE_DATA/pointing04-dev --workers 2 --report ...` when the evaluation
   set is there (or beside the development checkout; skipped, and said so, otherwise);
5. with `--soak S`, `roadgaze bench WORK/demo/drive.mp4 --loop-seconds S --memory --no-raw`;
6. the condition suite, `roadgaze eval $ROADGAZE_DATA/pointing04-dev --condition all` with
   `landmarks.enhance` off and auto, when the evaluation data is there (skip: `--no-conditions`);
   its two tables are written into docs/conditions.md between its `conditions-table` markers.

The block names the machine (CPU, cores, memory, OS, Python, MediaPipe and OpenCV versions) and
its load average before and after, because on a shared machine the speed figures move with it.
Progress goes to stderr, the Markdown block to stdout.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import itertools
import json
import os
import platform
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
from documented_figures import EVAL_METHODS as METHOD_LABELS  # noqa: E402
from documented_figures import POINTING04  # noqa: E402

BOLD = "service"


def say(text: str) -> None:
    print(f"measure-readme: {text}", file=sys.stderr, flush=True)


def roadgaze(*args: str) -> subprocess.CompletedProcess[str]:
    """`python -m roadgaze ARGS`; its stderr passes through, stdout is returned."""
    command = [sys.executable, "-m", "roadgaze", *args]
    say("$ roadgaze " + " ".join(args))
    result = subprocess.run(command, stdout=subprocess.PIPE, text=True, check=False)
    if result.returncode != 0:
        raise SystemExit(f"measure-readme: roadgaze {args[0]} failed (exit {result.returncode})")
    return result


def machine() -> str:
    cpu = "unknown CPU"
    memory_gib = float("nan")
    try:
        cpuinfo = Path("/proc/cpuinfo").read_text()
        cpu = re.search(r"model name\s*:\s*(.+)", cpuinfo).group(1).strip()  # type: ignore[union-attr]
        meminfo = Path("/proc/meminfo").read_text()
        memory_gib = int(re.search(r"MemTotal:\s*(\d+)", meminfo).group(1)) / 2**20  # type: ignore[union-attr]
    except (OSError, AttributeError):
        pass
    versions = []
    for name in ("mediapipe", "opencv-contrib-python", "opencv-python-headless", "eclipse-zenoh"):
        try:
            versions.append(f"{name} {importlib.metadata.version(name)}")
        except importlib.metadata.PackageNotFoundError:
            continue
    return (
        f"{cpu}, {os.cpu_count()} cores, {memory_gib:.0f} GiB, {platform.platform()}, "
        f"Python {platform.python_version()}; {', '.join(versions)}"
    )


def load_average() -> str:
    try:
        return " / ".join(f"{value:.1f}" for value in os.getloadavg())
    except OSError:
        return "unknown"


def demo(work: Path) -> dict[str, Any]:
    started = time.perf_counter()
    result = roadgaze("demo", "--out", str(work / "demo"))
    wall_s = time.perf_counter() - started
    split = re.search(r"render ([\d.]+) s, service ([\d.]+) s, total ([\d.]+) s", result.stdout)
    summary = re.search(r"demo: (\d+) frames.*MAE ([\d.]+) deg", result.stdout)
    return {
        "wall_s": wall_s,
        "render_s": float(split.group(1)) if split else None,
        "service_s": float(split.group(2)) if split else None,
        "frames": int(summary.group(1)) if summary else None,
        "mae_deg": float(summary.group(2)) if summary else None,
    }


def bench(video: Path, repeat: int) -> dict[str, Any]:
    args = ["bench", str(video), "--json", "--repeat", str(repeat), "--latency"]
    result: dict[str, Any] = json.loads(roadgaze(*args).stdout)
    return result


def synth_measure() -> list[tuple[str, float]]:
    """(|yaw| range, Center-CE MAE) rows of `roadgaze synth --measure`."""
    table = roadgaze("synth", "--measure").stdout
    rows = re.findall(r"^\s*(\d+-\d+)\s+\d+\s+\d+\s+([\d.]+)", table, flags=re.MULTILINE)
    return [(label, float(mae)) for label, mae in rows]


def soak(video: Path, seconds: float) -> dict[str, Any]:
    args = ["bench", str(video), "--json", "--loop-seconds", f"{seconds:g}", "--memory", "--no-raw"]
    result: dict[str, Any] = json.loads(roadgaze(*args).stdout)
    return result


def evaluate(work: Path) -> dict[str, Any] | None:
    if not POINTING04.is_dir():
        say(f"{POINTING04} not found: no accuracy figures")
        return None
    report = work / "eval-report.json"
    started = time.perf_counter()
    roadgaze("eval", str(POINTING04), "--workers", "2", "--report", str(report), "--no-progress")
    document: dict[str, Any] = json.loads(report.read_text())
    document["wall_s"] = time.perf_counter() - started
    return document


CONDITIONS_DOC = REPO / "docs" / "conditions.md"
CONDITIONS_MARKERS = ("<!-- conditions-table:start -->", "<!-- conditions-table:end -->")


def condition_tables() -> str | None:
    """The condition suite's tables without and with the front end, as Markdown; None without
    the evaluation data."""
    if not POINTING04.is_dir():
        say(f"{POINTING04} not found: no condition tables")
        return None
    parts = []
    for mode in ("off", "auto"):
        started = time.perf_counter()
        output = roadgaze(
            "eval",
            str(POINTING04),
            "--condition",
            "all",
            "--workers",
            "2",
            "--no-progress",
            "--set",
            f"landmarks.enhance={mode}",
        ).stdout
        lines = output.splitlines()
        first = next((i for i, line in enumerate(lines) if line.startswith("|")), len(lines))
        # The first table (the per-subject one follows it after a blank line).
        table = list(itertools.takewhile(lambda line: line.startswith("|"), lines[first:]))
        parts += [
            f"`landmarks.enhance = {mode}` (`roadgaze eval $ROADGAZE_DATA/pointing04-dev "
            f"--condition all --set landmarks.enhance={mode}`, "
            f"{time.perf_counter() - started:.0f} s):",
            "",
            *table,
            "",
        ]
    return "\n".join(parts).rstrip("\n")


def write_condition_tables(tables: str) -> None:
    """Replace the block between the markers of docs/conditions.md with `tables`."""
    text = CONDITIONS_DOC.read_text(encoding="utf-8")
    start, end = CONDITIONS_MARKERS
    head, found, rest = text.partition(start)
    _, found_end, tail = rest.partition(end)
    if not found or not found_end:
        raise SystemExit(
            f"measure-readme: the markers {start} / {end} are missing in {CONDITIONS_DOC}"
        )
    CONDITIONS_DOC.write_text(f"{head}{start}\n{tables}\n{end}{tail}", encoding="utf-8")
    say(f"wrote {CONDITIONS_DOC}")


def markdown(
    host: str,
    loads: tuple[str, str],
    demo_run: dict[str, Any],
    bench_run: dict[str, Any],
    synth_rows: list[tuple[str, float]],
    eval_run: dict[str, Any] | None,
    soak_run: dict[str, Any] | None,
) -> str:
    stages = bench_run["stages"]
    raw = bench_run.get("raw_mediapipe") or {}
    latency = bench_run.get("latency") or {}
    lines = [
        f"Measured on: {host}. Load average (1/5/15 min) {loads[0]} before, {loads[1]} after "
        "(a shared machine: speed figures move with the load). "
        "Regenerate with `.venv/bin/python scripts/measure-readme.py`.",
        "",
        "| figure | value | command |",
        "|---|---|---|",
        f"| demo, wall time | {demo_run['wall_s']:.1f} s (render {demo_run['render_s']} s, service "
        f"{demo_run['service_s']} s; {demo_run['frames']} frames; smoothed yaw MAE "
        f"{demo_run['mae_deg']} deg) | `roadgaze demo` |",
        f"| landmark stage | median {stages['landmarks']['median_ms']:.1f} ms, p99 "
        f"{stages['landmarks']['p99_ms']:.1f} ms | `roadgaze bench drive.mp4 --json --repeat "
        f"{bench_run['passes']} --latency` |",
        f"| whole frame | median {stages['total']['median_ms']:.1f} ms (overhead ratio "
        f"{bench_run['overhead_ratio']:.3f}) | same |",
        f"| throughput | {bench_run['pipeline_fps']} fps; MediaPipe alone "
        f"{bench_run['raw_mediapipe_fps']} fps; ratio_to_raw {bench_run['ratio_to_raw']} (passes: "
        f"{', '.join(map(str, raw.get('ratios', [])))}); median_ratio_to_raw "
        f"{raw.get('median_ratio_to_raw')} | same |",
        f"| CPU per frame | {bench_run['cpu_ms_per_frame']} ms (MediaPipe alone "
        f"{raw.get('cpu_ms_per_frame')} ms) | same |",
        f"| capture to Zenoh delivery (a pass at the drive's frame rate) | p50 "
        f"{latency.get('p50_ms')} ms, p99 {latency.get('p99_ms')} ms ({latency.get('received')} "
        f"of {latency.get('published')} received; target p99 <= landmark p99 "
        f"{latency.get('landmarks_p99_ms')} + 2 ms = {latency.get('target_p99_ms')} ms: "
        f"{'met' if latency.get('meets_target') else 'not met'}; of which up to the publish p50 "
        f"{latency.get('to_publish_p50_ms')} / p99 {latency.get('to_publish_p99_ms')} ms, Zenoh "
        f"delivery to a subscriber in another process p50 {latency.get('delivery_p50_ms')} / p99 "
        f"{latency.get('delivery_p99_ms')} ms) | same |",
    ]
    if soak_run is not None:
        memory = soak_run["memory"]
        lines.append(
            f"| resident memory over a {memory['wall_s']:.0f} s replay loop | grew "
            f"{memory['rss_growth_mb']} MiB (baseline {memory['rss_baseline_mb']} MiB, end "
            f"{memory['rss_end_mb']}, peak {memory['rss_peak_mb']}; {soak_run['frames']} frames) "
            f"| `roadgaze bench drive.mp4 --loop-seconds {memory['wall_s']:.0f} --memory` |"
        )
    if synth_rows:
        ranges = " / ".join(f"{mae:.1f}" for _, mae in synth_rows[:-1])
        labels = " / ".join(label for label, _ in synth_rows[:-1])
        lines.append(
            f"| yaw recovery on synthetic stills | service yaw (full range) MAE {ranges} deg for "
            f"\\|yaw\\| in {labels} (all: {synth_rows[-1][1]:.1f}) | `roadgaze synth --measure` |"
        )
    if eval_run is not None:
        lines += [
            "",
            f"Accuracy on Pointing'04 subjects 1-10, \\|yaw\\| <= 60 (`roadgaze eval "
            f"$ROADGAZE_DATA/pointing04-dev --workers 2`, {eval_run['wall_s']:.0f} s):",
            "",
            "| method | MAE (deg) | RMSE | median | face found |",
            "|---|---|---|---|---|",
        ]
        for method, label in METHOD_LABELS.items():
            stats = eval_run["ranges"]["abs_yaw_le_60"].get(method)
            if stats is None:
                continue
            bold = "**" if method == BOLD else ""
            lines.append(
                f"| {label} | {bold}{stats['mae_deg']:.2f}{bold} | {stats['rmse_deg']:.2f} | "
                f"{stats['median_abs_error_deg']:.2f} | {100 * stats['detection_rate']:.1f}% |"
            )
        cross = eval_run.get("cross_validation")
        if cross is not None:
            ranges = cross["ranges"]
            lines += [
                "",
                "With the blend's two constants re-fitted leaving each subject out, the service's "
                f"yaw gives {ranges['abs_yaw_le_60']['service_cv']['mae_deg']:.2f} within +-60 "
                f"and {ranges['all']['service_cv']['mae_deg']:.2f} over all poses.",
            ]
    return "\n".join(lines)


def check_documents(work: Path | None, cheap: bool, update: bool, only: str | None) -> int:
    from documented_figures import FIGURES, check_figures

    figures = [
        figure
        for figure in FIGURES
        if (figure.cheap or not cheap) and (only is None or only in figure.name)
    ]
    with tempfile.TemporaryDirectory(prefix="roadgaze-figures-") as scratch:
        folder = work or Path(scratch)
        folder.mkdir(parents=True, exist_ok=True)
        problems = check_figures(figures, folder, update=update, say=say)
    for problem in problems:
        print(("updated " if update else "") + str(problem))
    places = sum(len(figure.places) for figure in figures)
    say(f"{len(figures)} commands, {places} places, {len(problems)} differences")
    return 1 if problems and not update else 0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--work", type=Path, help="folder for the runs (default: a temporary one)")
    parser.add_argument("--repeat", type=int, default=3, help="bench passes (default 3)")
    parser.add_argument("--no-eval", action="store_true", help="skip the accuracy run")
    parser.add_argument(
        "--no-conditions", action="store_true", help="skip the condition suite (docs/conditions.md)"
    )
    parser.add_argument(
        "--soak", type=float, default=0.0, metavar="S", help="also a memory run of S seconds"
    )
    parser.add_argument(
        "--render",
        type=Path,
        metavar="WORK",
        help="print the block again from the measured.json of an earlier run's --work folder",
    )
    parser.add_argument(
        "--check", action="store_true", help="compare the documented figures with their commands"
    )
    parser.add_argument("--cheap", action="store_true", help="with --check: the quick ones only")
    parser.add_argument(
        "--only", metavar="TEXT", help="with --check/--update: the figures whose name holds TEXT"
    )
    parser.add_argument(
        "--update", action="store_true", help="write the commands' figures into the documents"
    )
    args = parser.parse_args()
    if args.check or args.update:
        return check_documents(args.work, args.cheap, args.update, args.only)
    if args.render is not None:
        saved = json.loads((args.render / "measured.json").read_text())
        print(markdown(**saved))
        return 0
    with tempfile.TemporaryDirectory(prefix="roadgaze-measure-") as scratch:
        work = args.work or Path(scratch)
        work.mkdir(parents=True, exist_ok=True)
        before = load_average()
        demo_run = demo(work)
        video = work / "demo" / "drive.mp4"
        bench_run = bench(video, args.repeat)
        synth_rows = synth_measure()
        eval_run = None if args.no_eval else evaluate(work)
        soak_run = soak(video, args.soak) if args.soak else None
        tables = None if args.no_conditions else condition_tables()
        if tables is not None:
            write_condition_tables(tables)
        after = load_average()
        measured: dict[str, Any] = {
            "host": machine(),
            "loads": (before, after),
            "demo_run": demo_run,
            "bench_run": bench_run,
            "synth_rows": synth_rows,
            "eval_run": eval_run,
            "soak_run": soak_run,
        }
        (work / "measured.json").write_text(json.dumps(measured, indent=2) + "\n")
        print(markdown(**measured))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
