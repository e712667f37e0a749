"""The dossier scored by Euro NCAP's own rating calculator (`euroncap-rating-2026`, the extra
`roadgaze[euroncap]`), run as its users run it: its command line, in a subprocess.

`generate-template` gives the template the dossier fills; `preprocess` selects the verification
tests from the dossier's predictions (at random, as Euro NCAP's laboratories do) and writes the
verification sheet; each selected test is answered by running its scenario through the service
again, under the noise variable the calculator assigned to it; `compute-score` scores the
answered workbook, and its report gives Driver Monitoring's points.
"""

from __future__ import annotations

import logging
import subprocess
import sys
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path

from roadgaze.conformance.dossier import GREEN, Dossier, Runner, run_under
from roadgaze.conformance.dossier_rows import NOISE_VARIABLES
from roadgaze.conformance.dossier_xlsx import Score, read_score, read_verification, write_answers
from roadgaze.conformance.model import Scenario
from roadgaze.errors import ConfigError

log = logging.getLogger(__name__)

PACKAGE = "euroncap-rating-2026"
PINNED = "5.4.9"
"""The calculator whose template `dossier_rows` was read from (constraints.txt pins it)."""
INSTALL = "pip install -c constraints.txt -e '.[euroncap]' (or pip install 'roadgaze[euroncap]')"
TIMEOUT_S = 900.0
"""The longest one calculator step may take (each takes seconds to a minute)."""


def installed_version() -> str | None:
    """The installed calculator's version (None: not installed)."""
    try:
        return metadata.version(PACKAGE)
    except metadata.PackageNotFoundError:
        return None


def require_calculator() -> str:
    """The installed calculator's version; a one-line `ConfigError` saying how to install it
    when it is missing or of another minor version than the pinned one."""
    version = installed_version()
    if version is None:
        raise ConfigError(f"--dossier and --score need Euro NCAP's rating calculator: {INSTALL}")
    if version.split(".")[:2] != PINNED.split(".")[:2]:
        raise ConfigError(
            f"{PACKAGE} {version} is installed; roadgaze's dossier reads the sheet of {PINNED}: "
            f"{INSTALL}"
        )
    return version


class Calculator:
    """The calculator's Safe Driving commands, each a subprocess working in `workdir` (its log,
    `euroncap_rating_2026.log`, stays there)."""

    def __init__(self, workdir: Path) -> None:
        # Absolute: the commands run in it, and its path is passed to them as their output.
        self.workdir = workdir.resolve()
        self.workdir.mkdir(parents=True, exist_ok=True)

    def _run(self, command: str, *args: str) -> None:
        argv = [sys.executable, "-P", "-m", "euroncap_rating_2026", "safe_driving", command, *args]
        try:
            done = subprocess.run(
                argv,
                cwd=self.workdir,
                capture_output=True,
                text=True,
                timeout=TIMEOUT_S,
                check=False,
            )
        except subprocess.TimeoutExpired as exc:
            took = f"Euro NCAP's calculator ({command}) took over {TIMEOUT_S:g} s"
            raise ConfigError(took) from exc
        said = [line.strip() for line in (done.stdout + done.stderr).splitlines() if line.strip()]
        for line in said:
            if line.startswith(("Error", "Warning")):
                log.warning("euroncap_rating_2026 %s: %s", command, line)
        if done.returncode != 0:
            last = said[-1] if said else "no output"
            raise ConfigError(
                f"Euro NCAP's calculator ({command}) failed with exit {done.returncode}: {last} "
                f"(log: {self.workdir / 'euroncap_rating_2026.log'})"
            )

    def template(self) -> Path:
        """A fresh Safe Driving template (`generate-template`)."""
        self._run("generate-template")
        return self._output(self.workdir / "sd_template.xlsx", "generate-template")

    def preprocess(self, dossier: Path) -> Path:
        """The dossier with the verification sheet of the tests selected from it."""
        self._run("preprocess", "-i", str(dossier.resolve()), "-o", str(self.workdir))
        return self._output(self.workdir / "sd_preprocessed_template.xlsx", "preprocess")

    def compute_score(self, verified: Path) -> Path:
        """The calculator's report on the answered workbook."""
        before = set(self.workdir.glob("sd_*_report.xlsx"))
        self._run("compute-score", "-i", str(verified.resolve()), "-o", str(self.workdir))
        written = sorted(set(self.workdir.glob("sd_*_report.xlsx")) - before)
        if not written:
            raise ConfigError(
                f"Euro NCAP's calculator (compute-score) wrote no report in {self.workdir}"
            )
        return written[-1]

    def _output(self, path: Path, command: str) -> Path:
        if not path.is_file():
            raise ConfigError(f"Euro NCAP's calculator ({command}) did not write {path}")
        return path


@dataclass(frozen=True, slots=True)
class Answer:
    """One verification test answered: the cell it checks, its noise variable, the value."""

    row: int
    column: str
    requirement: str
    noise: str
    value: str
    why: str


@dataclass(frozen=True, slots=True)
class Scored:
    """The calculator's Driver Monitoring score and how its tests were answered."""

    score: Score
    answers: tuple[Answer, ...]
    notes: tuple[str, ...]
    """What the calculator wrote instead of tests (e.g. a non-functional mandatory noise
    variable)."""
    report: Path


def answer_general(dossier: Dossier, text: str) -> str:
    """The dossier's answer to the general requirement worded `text` by the calculator."""
    for general in dossier.general:
        if general.requirement.text == text:
            return general.value
    raise ConfigError(
        f"Euro NCAP's calculator asks a general requirement roadgaze does not know: {text!r}; "
        f"install the pinned calculator ({INSTALL})"
    )


def answer_test(
    dossier: Dossier,
    row: int,
    column: str,
    noise: str,
    scenarios: list[Scenario],
    runner: Runner,
    ignore_noise: bool = False,
) -> tuple[bool, str]:
    """Run the scenarios behind prediction cell (`row`, `column`) again, under `noise` (the
    noise variable the calculator assigned, "" none; ignored with `ignore_noise`)."""
    cell = dossier.cell(row, column)
    if cell is None or cell.colour != GREEN:
        return False, f"cell {column}{row} is not GREEN in the dossier"
    variable = None
    if noise and not ignore_noise:
        variable = next((v for v in NOISE_VARIABLES if v.element == noise), None)
        if variable is None:
            return False, f"unknown noise variable {noise!r}"
    return run_under(cell.keys, variable, scenarios, runner)


def score(
    dossier: Dossier,
    dossier_path: Path,
    calculator: Calculator,
    scenarios: list[Scenario],
    runner: Runner,
    ignore_noise: bool = False,
) -> Scored:
    """Preprocess `dossier_path`, answer every selected test and general requirement, compute
    the score. `ignore_noise` runs each test as it is, without its noise variable."""
    preprocessed = calculator.preprocess(dossier_path)
    verification = read_verification(preprocessed)
    values = {line: answer_general(dossier, text) for line, text in verification.general}
    answers = []
    for test in verification.tests:
        passed, why = answer_test(
            dossier, test.row, test.column, test.noise, scenarios, runner, ignore_noise
        )
        value = "PASS" if passed else "FAIL"
        values[test.line] = value
        answers.append(Answer(test.row, test.column, test.requirement, test.noise, value, why))
        noise = "" if not test.noise else f" ({test.noise}{', ignored' if ignore_noise else ''})"
        log.info(
            "euroncap verification %s%d %s%s: %s (%s)",
            test.column,
            test.row,
            test.requirement,
            noise,
            value,
            why,
        )
    verified = write_answers(
        preprocessed, verification.value_column, values, calculator.workdir / "sd_verified.xlsx"
    )
    report = calculator.compute_score(verified)
    return Scored(read_score(report), tuple(answers), verification.notes, report)
