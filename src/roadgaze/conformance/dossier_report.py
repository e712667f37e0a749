"""The dossier in Markdown: the measured sheet (stdout, `DIR/dossier.md`), the score lines, and
the mapping table of docs/euroncap.md, generated from the same table the code fills the sheet
from (`roadgaze.conformance.dossier_rows`), so the page and the code cannot disagree."""

from __future__ import annotations

from collections.abc import Iterable

from roadgaze.config import MonitorConfig
from roadgaze.conformance.dossier import GREEN, Cell, Dossier
from roadgaze.conformance.dossier_rows import (
    ASSUMPTIONS,
    GENERAL_REQUIREMENTS,
    NOISE_VARIABLES,
    ROWS,
    TABLES,
    Evidence,
    GeneralRequirement,
    SheetRow,
)
from roadgaze.conformance.dossier_score import Scored
from roadgaze.conformance.dossier_xlsx import Score
from roadgaze.monitor.protocols import Rule

DOC_START, DOC_END = "<!-- euroncap-rows:start -->", "<!-- euroncap-rows:end -->"


def _escape(text: str) -> str:
    return text.replace("|", "\\|")


def _table(header: Iterable[str], rows: Iterable[Iterable[str]]) -> list[str]:
    header = list(header)
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(_escape(cell) for cell in row) + " |" for row in rows]
    return lines


def _rows_of(table: str) -> list[SheetRow]:
    return [row for row in ROWS if row.table == table]


def _shown(cell: Cell) -> str:
    if cell.colour is None:
        return "n/a"
    return f"{'GREEN' if cell.colour == GREEN else 'RED'} ({cell.why})"


def dossier_markdown(dossier: Dossier) -> str:
    """The filled sheet with what was measured behind each cell."""
    lines = [f"## Driver monitoring prediction ({dossier.cabin.upper()} cabin)", ""]
    for table in TABLES:
        rows = _rows_of(table)
        lines += [f"### {table}", ""]
        body = []
        for row in rows:
            cells = [dossier.cell(row.row, column) for column in ("D", "E", "F")]
            body.append([str(row.row), row.name, *(_shown(c) for c in cells if c is not None)])
        lines += [*_table(["row", "task / movement / location", *rows[0].headers], body), ""]
    lines += ["### Noise variables", ""]
    noise = [[str(n.variable.row), n.variable.element, n.performance, n.why] for n in dossier.noise]
    lines += [*_table(["row", "noise variable", "performance", "why"], noise), ""]
    lines += ["### General requirements (answered in the verification sheet)", ""]
    general = [[g.requirement.text, g.value, g.why] for g in dossier.general]
    lines += _table(["requirement", "answer", "why"], general)
    return "\n".join(lines) + "\n"


def points(value: float | None) -> str:
    return "unassessed" if value is None else f"{value:g}"


def score_lines(official: Scored, dossier: Dossier, alone: Score | None = None) -> list[str]:
    """The score as printed: `Driver Monitoring: X / 25 points`, its categories, what holds it
    at 0, the rows alone (when held), and the assumptions."""
    score = official.score
    lines = [f"Driver Monitoring: {points(score.points)} / {score.max_points:g} points"]
    lines += [f"  {name}: {points(got)} / {most:g}" for name, got, most in score.categories]
    lines += [f"  held at 0 by {gate}" for gate in dossier.gates()]
    if alone is not None:
        earned = ", ".join(f"{name} {got:g}" for name, got, _ in alone.categories if got)
        lines.append(
            f"  the rows alone, were those met: {points(alone.points)} / {alone.max_points:g}"
            + (f" ({earned})" if earned else "")
            + "; the same calculator on a copy of the dossier with the mandatory noise variables "
            "functional and the general requirements met: not a score"
        )
    lines.append(f"  {len(official.answers)} verification tests answered by the service")
    lines += [f"  calculator: {note}" for note in official.notes]
    lines += [f"Assumed: {assumption}" for assumption in ASSUMPTIONS]
    return lines


def _evidence(evidence: Evidence) -> str:
    if evidence is None:
        return "n/a (sheet)"
    return ", ".join(f"`{key}`" for key in evidence) if evidence else "none yet"


def _rule_names(rules: tuple[Rule, ...]) -> str:
    return ", ".join(f"`{rule.key}`" for rule in rules) if rules else "none yet"


def _setting(rule: Rule, config: MonitorConfig) -> str:
    value = rule.value(config)
    shown = "unset" if value is None else f"{value:g} {rule.unit}"
    return f"`{rule.config_key}` = {shown}"


def _general_basis(general: GeneralRequirement) -> str:
    parts = []
    if general.evidence:
        parts.append("PASS when " + ", ".join(f"`{k}`" for k in general.evidence) + " passed")
    if general.basis:
        parts.append(general.basis)
    if general.integrator:
        parts.append(f"taken as met: {general.integrator}")
    if general.noise:
        parts.append(f"N/A when {general.noise} is Functional")
    if general.missing:
        parts.append(f"{'else ' if parts else ''}FAIL: {general.missing}")
    return "; ".join(parts)


def mapping_markdown(config: MonitorConfig) -> str:
    """docs/euroncap.md's tables: each sheet row -> the requirements behind its cells -> the
    rules, their settings (with `config`'s values) and sources."""
    lines: list[str] = []
    for table in TABLES:
        rows = _rows_of(table)
        header = ["row", "task / movement / location", *rows[0].headers, "rules"]
        body = [
            [str(r.row), r.name, *(_evidence(e) for e in r.cells), _rule_names(r.rules)]
            for r in rows
        ]
        lines += [f"**{table}**", "", *_table(header, body), ""]
    rules = list(dict.fromkeys(rule for row in ROWS for rule in row.rules))
    lines += ["**Rules**", ""]
    lines += _table(
        ["rule", "setting (default)", "source"],
        ([f"`{r.key}`", _setting(r, config), r.source] for r in rules),
    )
    lines += ["", "**Noise variables**", ""]
    lines += _table(
        ["row", "noise variable", "mandatory", "rendered by"],
        (
            [
                str(v.row),
                v.element,
                "yes" if v.mandatory else "no",
                f"`{v.variant.__name__}`" if v.variant else "not yet",
            ]
            for v in NOISE_VARIABLES
        ),
    )
    lines += ["", "**General requirements**", ""]
    lines += _table(
        ["requirement", "answered"], ([g.text, _general_basis(g)] for g in GENERAL_REQUIREMENTS)
    )
    return "\n".join(lines)


def doc_block(config: MonitorConfig) -> str:
    """The generated block of docs/euroncap.md, markers included."""
    return f"{DOC_START}\n{mapping_markdown(config)}\n{DOC_END}"
