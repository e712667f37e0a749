"""The conformance table: Markdown (stdout, `conformance.md`, the README) and JSON."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from roadgaze.conformance.model import Outcome
from roadgaze.conformance.run import SuiteRun

HEADER = (
    "| scenario | requirement | source | expected (s) | measured (s) | result |",
    "|---|---|---|---|---|---|",
)


def _window(outcome: Outcome) -> str:
    window = outcome.requirement.window_s
    return "none" if window is None else f"{window[0]:.2f}-{window[1]:.2f}"


def _measured(outcome: Outcome) -> str:
    return "none" if outcome.measured_s is None else f"{outcome.measured_s:.2f}"


def row(outcome: Outcome) -> str:
    """One table row; `|` in a text is escaped."""
    cells = (
        f"`{outcome.scenario}`",
        outcome.requirement.text,
        outcome.requirement.source,
        _window(outcome),
        _measured(outcome),
        "**FAIL**" if outcome.result == "FAIL" else outcome.result,
    )
    return "| " + " | ".join(cell.replace("|", "\\|") for cell in cells) + " |"


def markdown_table(outcomes: tuple[Outcome, ...] | list[Outcome]) -> str:
    return "\n".join([*HEADER, *(row(outcome) for outcome in outcomes)])


def summary_line(run: SuiteRun, protocol: str) -> str:
    failed = len(run.failed)
    judged = sum(outcome.requirement.applies for outcome in run.outcomes)
    other = len(run.outcomes) - judged
    return (
        f"protocol {protocol}: {judged - failed} of {judged} requirements PASS, {failed} FAIL"
        + (f", {other} of other protocols not judged (N/A)" if other else "")
        + f"; {run.scenarios} scenarios in {run.wall_s:.0f} s"
    )


def to_json(run: SuiteRun, protocol: str, fps: float) -> dict[str, Any]:
    return {
        "protocol": protocol,
        "fps": fps,
        "scenarios": run.scenarios,
        "requirements": sum(outcome.requirement.applies for outcome in run.outcomes),
        "not_applicable": sum(not outcome.requirement.applies for outcome in run.outcomes),
        "failed": len(run.failed),
        "wall_s": round(run.wall_s, 1),
        "outcomes": [outcome.to_json() for outcome in run.outcomes],
    }


def write_reports(run: SuiteRun, protocol: str, fps: float, out_dir: Path) -> tuple[Path, Path]:
    """`conformance.md` and `conformance.json` in `out_dir`; returns both paths."""
    out_dir.mkdir(parents=True, exist_ok=True)
    markdown = out_dir / "conformance.md"
    text = f"# Conformance\n\n{summary_line(run, protocol)}\n\n{markdown_table(run.outcomes)}\n"
    markdown.write_text(text, encoding="utf-8")
    data = out_dir / "conformance.json"
    data.write_text(json.dumps(to_json(run, protocol, fps), indent=1) + "\n", encoding="utf-8")
    return markdown, data
